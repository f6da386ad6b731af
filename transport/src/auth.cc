#include "pidlab/transport/auth.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <iterator>
#include <vector>

namespace pidlab::transport {
namespace {

bool SodiumReady() {
  static const bool ready = sodium_init() >= 0;
  return ready;
}

int64_t ReadInt64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<int64_t>(v);
}

}  // namespace

namespace {

// LoadAuthKey() with the refusal's message in *error.
bool LoadAuthKeyOrExplain(const std::string& path, AuthKey* key, std::string* error) {
  auto fail = [&](const std::string& what) {
    if (error) *error = "--auth-key '" + path.substr(0, 200) + "': " + what;
    return false;
  };
  if (!SodiumReady()) return fail("libsodium could not be initialised");
  // Opened without blocking and checked before a byte is read, as
  // io::OpenRegularFile does (transport sits beside io, not above it): a
  // FIFO would otherwise wait for a writer for ever.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return fail("cannot be read");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return fail("is not a regular file");
  }
  std::vector<char> bytes;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 || bytes.size() + static_cast<std::size_t>(n) > (std::size_t{1} << 20)) {
      ::close(fd);
      sodium_memzero(bytes.data(), bytes.size());
      return fail(n < 0 ? "cannot be read" : "is larger than 1 MiB");
    }
    bytes.insert(bytes.end(), buf, buf + n);
  }
  ::close(fd);
  if (bytes.size() < kMinAuthKeyFileBytes)
    return fail("holds " + std::to_string(bytes.size()) + " bytes, at least " +
                std::to_string(kMinAuthKeyFileBytes) + " are needed (head -c 32 /dev/urandom > FILE)");
  crypto_hash_sha256(key->bytes.data(), reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  sodium_memzero(bytes.data(), bytes.size());
  return true;
}

}  // namespace

Status LoadAuthKey(const std::string& path, AuthKey* key) {
  std::string why;
  if (!LoadAuthKeyOrExplain(path, key, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

std::array<uint8_t, kAuthTagBytes> AuthTag(const AuthKey& key, const std::string& channel,
                                           const void* payload, std::size_t size) {
  SodiumReady();
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key.bytes.data(), key.bytes.size());
  // The channel's length first, so channel and payload cannot be re-split.
  const uint32_t n = static_cast<uint32_t>(channel.size());
  const unsigned char len[4] = {static_cast<unsigned char>(n >> 24), static_cast<unsigned char>(n >> 16),
                                static_cast<unsigned char>(n >> 8), static_cast<unsigned char>(n)};
  crypto_auth_hmacsha256_update(&state, len, sizeof len);
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const unsigned char*>(channel.data()),
                                channel.size());
  crypto_auth_hmacsha256_update(&state, static_cast<const unsigned char*>(payload), size);
  std::array<uint8_t, kAuthTagBytes> tag{};
  crypto_auth_hmacsha256_final(&state, tag.data());
  return tag;
}

AuthResult ReplayGuard::Check(const AuthKey& key, const std::string& channel, const void* datagram,
                              std::size_t size, int64_t now_utime, double now_s) {
  // fingerprint (8), utime (8): every pidlab message starts so.
  if (size < kAuthTagBytes + 16) return AuthResult::kUnauthenticated;
  const auto* bytes = static_cast<const uint8_t*>(datagram);
  const std::size_t payload = size - kAuthTagBytes;
  const auto tag = AuthTag(key, channel, bytes, payload);
  if (crypto_verify_32(tag.data(), bytes + payload) != 0) return AuthResult::kUnauthenticated;
  const int64_t utime = ReadInt64(bytes + 8);
  if (std::abs(static_cast<double>(now_utime) - static_cast<double>(utime)) > kReplayWindowS * 1e6)
    return AuthResult::kReplayed;
  if (now_s - generation_start_s_ > kReplayWindowS) {
    previous_.swap(current_);
    current_.clear();
    generation_start_s_ = now_s;
  }
  uint64_t id = 0;
  std::memcpy(&id, tag.data(), sizeof id);
  if (previous_.count(id) || !current_.insert(id).second) return AuthResult::kReplayed;
  return AuthResult::kAccepted;
}

}  // namespace pidlab::transport
