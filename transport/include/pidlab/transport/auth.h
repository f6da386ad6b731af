#pragma once
// Message authentication for the trio (docs/security.md). With a shared key,
// every datagram carries a 32-byte HMAC-SHA256 tag (libsodium) over its
// channel name and its payload; the payload holds the episode id and the
// sender's utime, so a tag binds the message to its channel and episode and
// dates it. A receiver drops, and counts, a datagram whose tag does not
// verify (unauthenticated or forged), one dated outside the replay window,
// and an exact repeat of one it has already accepted (replayed).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_set>

#include "pidlab/spec/status.h"

namespace pidlab::transport {

inline constexpr std::size_t kAuthTagBytes = 32;
/// A key file must hold at least this many bytes (e.g. head -c 32 /dev/urandom).
inline constexpr std::size_t kMinAuthKeyFileBytes = 16;
/// Messages dated further than this from the receiver's clock are replays, s.
inline constexpr double kReplayWindowS = 30.0;
/// Environment variable through which `pidlab launch` passes the key file to COMMAND.
inline constexpr const char* kAuthKeyFileEnv = "PIDLAB_AUTH_KEY_FILE";

struct AuthKey {
  std::array<uint8_t, 32> bytes{};
};

/// The key of a key file: SHA-256 of its contents (at least
/// kMinAuthKeyFileBytes bytes, at most 1 MiB). A failed Status (kInvalidInput) naming the
/// file and what is wrong.
Status LoadAuthKey(const std::string& path, AuthKey* key);

/// The tag of `payload` on `channel` (the full, prefixed channel name).
std::array<uint8_t, kAuthTagBytes> AuthTag(const AuthKey& key, const std::string& channel,
                                           const void* payload, std::size_t size);

enum class AuthResult { kAccepted, kUnauthenticated, kReplayed };

/// What a receiver remembers to refuse replays: the tags it accepted within
/// the replay window (two generations, so memory is bounded by the traffic of
/// two windows).
class ReplayGuard {
 public:
  /// Checks `datagram` (payload then tag) received on `channel` at now_s
  /// (monotonic) with wall clock now_utime. On kAccepted the payload is the
  /// first size - kAuthTagBytes bytes.
  AuthResult Check(const AuthKey& key, const std::string& channel, const void* datagram, std::size_t size,
                   int64_t now_utime, double now_s);

 private:
  std::unordered_set<uint64_t> current_, previous_;
  double generation_start_s_ = -1e300;
};

}  // namespace pidlab::transport
