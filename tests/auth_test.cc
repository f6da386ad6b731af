// Message authentication (transport/auth.h): key files, the HMAC-SHA256 tag
// over channel and payload, and the replay guard's window and memory.

#include "pidlab/transport/auth.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "test_status.h"

namespace pidlab::transport {
namespace {

class KeyFile {
 public:
  explicit KeyFile(const std::string& contents) {
    char name[] = "/tmp/pidlab_auth_test_XXXXXX";
    const int fd = mkstemp(name);
    EXPECT_GE(fd, 0);
    if (fd >= 0) close(fd);
    path_ = name;
    std::ofstream(path_, std::ios::binary) << contents;
  }
  ~KeyFile() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

AuthKey Key(const std::string& contents) {
  KeyFile file(contents);
  AuthKey key;
  std::string error;
  EXPECT_TRUE(IsOk(LoadAuthKey(file.path(), &key)));
  return key;
}

/// A pidlab-like payload: fingerprint (8 bytes), utime (8, big-endian), body.
std::vector<uint8_t> Payload(int64_t utime, const std::string& body) {
  std::vector<uint8_t> p(16 + body.size(), 0xab);
  for (int i = 0; i < 8; ++i)
    p[static_cast<std::size_t>(8 + i)] = static_cast<uint8_t>(static_cast<uint64_t>(utime) >> (56 - 8 * i));
  for (std::size_t i = 0; i < body.size(); ++i) p[16 + i] = static_cast<uint8_t>(body[i]);
  return p;
}

/// payload then its tag, as a sender with `key` publishes it on `channel`.
std::vector<uint8_t> Datagram(const AuthKey& key, const std::string& channel,
                              const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> d(payload.size() + kAuthTagBytes);
  const auto tag = AuthTag(key, channel, payload.data(), payload.size());
  std::copy(payload.begin(), payload.end(), d.begin());
  std::copy(tag.begin(), tag.end(), d.begin() + static_cast<std::ptrdiff_t>(payload.size()));
  return d;
}

constexpr int64_t kNow = 1'700'000'000'000'000;  // utime, us

TEST(LoadAuthKey, TheKeyIsTheSha256OfTheFileSoTheSameFileGivesTheSameKey) {
  const AuthKey a = Key("0123456789abcdef0123456789abcdef");
  const AuthKey b = Key("0123456789abcdef0123456789abcdef");
  const AuthKey c = Key("0123456789abcdef0123456789abcdeF");
  EXPECT_EQ(a.bytes, b.bytes);
  EXPECT_NE(a.bytes, c.bytes);
  // SHA-256("0123456789abcdef0123456789abcdef") starts a0 b2 16 2b... : not the file's bytes.
  EXPECT_NE(std::string(a.bytes.begin(), a.bytes.end()).substr(0, 16), "0123456789abcdef");
}

TEST(LoadAuthKey, AFileShorterThanTheMinimumIsRefusedNamingItsSize) {
  KeyFile file(std::string(kMinAuthKeyFileBytes - 1, 'k'));
  AuthKey key;
  std::string error;
  EXPECT_FALSE(OkInto(LoadAuthKey(file.path(), &key), &error));
  EXPECT_NE(error.find(file.path()), std::string::npos) << error;
  EXPECT_NE(error.find("holds 15 bytes, at least 16"), std::string::npos) << error;
}

TEST(LoadAuthKey, AMissingFileIsRefusedNamingIt) {
  AuthKey key;
  std::string error;
  EXPECT_FALSE(OkInto(LoadAuthKey("/nonexistent/pidlab.key", &key), &error));
  EXPECT_NE(error.find("'/nonexistent/pidlab.key': cannot be read"), std::string::npos) << error;
}

TEST(LoadAuthKey, AFileOverOneMebibyteIsRefused) {
  KeyFile file(std::string((std::size_t{1} << 20) + 1, 'k'));
  AuthKey key;
  std::string error;
  EXPECT_FALSE(OkInto(LoadAuthKey(file.path(), &key), &error));
  EXPECT_NE(error.find("larger than 1 MiB"), std::string::npos) << error;
}

TEST(AuthTag, DependsOnTheKeyTheChannelAndEveryPayloadByte) {
  const AuthKey key = Key("the trio's shared secret key");
  const std::vector<uint8_t> p = Payload(kNow, "y=1.5");
  const auto tag = AuthTag(key, "PIDLAB_CONTROL", p.data(), p.size());
  EXPECT_EQ(tag, AuthTag(key, "PIDLAB_CONTROL", p.data(), p.size()));  // deterministic
  EXPECT_NE(tag, AuthTag(Key("another shared secret key"), "PIDLAB_CONTROL", p.data(), p.size()));
  EXPECT_NE(tag, AuthTag(key, "PIDLAB_PLANT_OUTPUT", p.data(), p.size()));
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::vector<uint8_t> q = p;
    q[i] ^= 1;
    EXPECT_NE(tag, AuthTag(key, "PIDLAB_CONTROL", q.data(), q.size())) << "byte " << i;
  }
}

TEST(AuthTag, ChannelAndPayloadCannotBeReSplit) {
  const AuthKey key = Key("the trio's shared secret key");
  // Channel "A" with payload "B" and channel "AB" with an empty payload: the
  // same bytes in a row, told apart by the channel's length in front.
  const std::vector<uint8_t> b = {'B'};
  EXPECT_NE(AuthTag(key, "A", b.data(), b.size()), AuthTag(key, "AB", b.data(), 0));
}

TEST(ReplayGuard, AcceptsAnAuthenticMessageOnceAndRefusesItsRepeat) {
  const AuthKey key = Key("the trio's shared secret key");
  const std::vector<uint8_t> d = Datagram(key, "PIDLAB_CONTROL", Payload(kNow, "u=2"));
  ReplayGuard dut;
  EXPECT_EQ(dut.Check(key, "PIDLAB_CONTROL", d.data(), d.size(), kNow, 100.0), AuthResult::kAccepted);
  EXPECT_EQ(dut.Check(key, "PIDLAB_CONTROL", d.data(), d.size(), kNow, 100.1), AuthResult::kReplayed);
}

TEST(ReplayGuard, RefusesAForgedTagAnotherKeyAnotherChannelAndAShortDatagram) {
  const AuthKey key = Key("the trio's shared secret key");
  const std::vector<uint8_t> d = Datagram(key, "PIDLAB_CONTROL", Payload(kNow, "u=2"));
  ReplayGuard dut;
  std::vector<uint8_t> forged = d;
  forged[17] ^= 0x40;  // the payload changed after tagging
  EXPECT_EQ(dut.Check(key, "PIDLAB_CONTROL", forged.data(), forged.size(), kNow, 1.0),
            AuthResult::kUnauthenticated);
  EXPECT_EQ(dut.Check(Key("another shared secret key"), "PIDLAB_CONTROL", d.data(), d.size(), kNow, 1.0),
            AuthResult::kUnauthenticated);
  EXPECT_EQ(dut.Check(key, "PIDLAB_PLANT_OUTPUT", d.data(), d.size(), kNow, 1.0),
            AuthResult::kUnauthenticated);
  EXPECT_EQ(dut.Check(key, "PIDLAB_CONTROL", d.data(), kAuthTagBytes + 15, kNow, 1.0),
            AuthResult::kUnauthenticated);
  // None of these used up the authentic message.
  EXPECT_EQ(dut.Check(key, "PIDLAB_CONTROL", d.data(), d.size(), kNow, 1.0), AuthResult::kAccepted);
}

TEST(ReplayGuard, AMessageDatedOutsideTheWindowIsAReplay) {
  const AuthKey key = Key("the trio's shared secret key");
  const int64_t window_us = static_cast<int64_t>(kReplayWindowS * 1e6);
  ReplayGuard dut;
  const std::vector<uint8_t> old = Datagram(key, "C", Payload(kNow - window_us - 1, "x"));
  const std::vector<uint8_t> future = Datagram(key, "C", Payload(kNow + window_us + 1, "x"));
  const std::vector<uint8_t> edge = Datagram(key, "C", Payload(kNow - window_us, "x"));
  EXPECT_EQ(dut.Check(key, "C", old.data(), old.size(), kNow, 1.0), AuthResult::kReplayed);
  EXPECT_EQ(dut.Check(key, "C", future.data(), future.size(), kNow, 1.0), AuthResult::kReplayed);
  EXPECT_EQ(dut.Check(key, "C", edge.data(), edge.size(), kNow, 1.0), AuthResult::kAccepted);
}

TEST(ReplayGuard, RemembersAcceptedTagsForAtLeastOneWindowOfItsClock) {
  const AuthKey key = Key("the trio's shared secret key");
  const std::vector<uint8_t> d = Datagram(key, "C", Payload(kNow, "x"));
  ReplayGuard dut;
  ASSERT_EQ(dut.Check(key, "C", d.data(), d.size(), kNow, 0.0), AuthResult::kAccepted);
  // Another message later starts a new generation; the first is still remembered.
  const std::vector<uint8_t> e = Datagram(key, "C", Payload(kNow, "y"));
  ASSERT_EQ(dut.Check(key, "C", e.data(), e.size(), kNow, kReplayWindowS + 1.0), AuthResult::kAccepted);
  EXPECT_EQ(dut.Check(key, "C", d.data(), d.size(), kNow, kReplayWindowS + 2.0), AuthResult::kReplayed);
  EXPECT_EQ(dut.Check(key, "C", e.data(), e.size(), kNow, kReplayWindowS + 2.0), AuthResult::kReplayed);
}

}  // namespace
}  // namespace pidlab::transport
