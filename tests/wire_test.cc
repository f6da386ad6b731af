// The wire checks (transport/wire.h): every pidlab message as LCM encodes it
// passes; a payload cut short, a length beyond the bytes present or beyond
// the protocol's limits, a string without its terminating NUL and an unknown
// fingerprint do not. Offsets: fingerprint (8) + utime, episode_id, step (24).

#include "pidlab/transport/wire.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_config_v1.hpp>
#include <pidlab/lcmt_episode_config_v2.hpp>
#include <pidlab/lcmt_episode_config_v3.hpp>
#include <pidlab/lcmt_episode_config_v4.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <string>
#include <vector>

#include "pidlab/transport/protocol.h"

namespace pidlab::transport {
namespace {

constexpr int kBody = 8 + 24;  // where the first field after the header starts

template <typename Message>
std::vector<uint8_t> Encode(const Message& m) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

template <typename Message>
bool Ok(const std::vector<uint8_t>& buf) {
  return WireLayoutOk(Message::getHash(), buf.data(), static_cast<int>(buf.size()));
}

void PutInt32(std::vector<uint8_t>* buf, int offset, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i)
    (*buf)[static_cast<std::size_t>(offset + i)] = static_cast<uint8_t>(u >> (24 - 8 * i));
}

pidlab::lcmt_trajectory_chunk Chunk(int count) {
  pidlab::lcmt_trajectory_chunk m{};
  m.count = count;
  m.y.assign(static_cast<std::size_t>(count), 1.0);
  m.u.assign(static_cast<std::size_t>(count), 2.0);
  m.n.assign(static_cast<std::size_t>(count), 3.0);
  return m;
}

TEST(WireLayout, EveryMessageAsEncodedPasses) {
  pidlab::lcmt_episode_config config{};
  config.num_size = 1;
  config.num = {1.0};
  config.den_size = 3;
  config.den = {1.0, 0.0, 0.0};
  config.plant_name = "double_integrator";
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config>(Encode(config)));
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config_v1>(Encode(pidlab::lcmt_episode_config_v1{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config_v2>(Encode(pidlab::lcmt_episode_config_v2{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config_v3>(Encode(pidlab::lcmt_episode_config_v3{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config_v4>(Encode(pidlab::lcmt_episode_config_v4{})));
  pidlab::lcmt_ready ready{};
  ready.role = "plant";
  ready.detail = "nonce";
  EXPECT_TRUE(Ok<pidlab::lcmt_ready>(Encode(ready)));
  pidlab::lcmt_episode_summary summary{};
  summary.message = "ok";
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_summary>(Encode(summary)));
  EXPECT_TRUE(Ok<pidlab::lcmt_trajectory_chunk>(Encode(Chunk(5))));
  pidlab::lcmt_disturbance_block block{};
  block.count = 2;
  block.n = {0.5, -0.5};
  EXPECT_TRUE(Ok<pidlab::lcmt_disturbance_block>(Encode(block)));
  EXPECT_TRUE(Ok<pidlab::lcmt_plant_output>(Encode(pidlab::lcmt_plant_output{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_control_command>(Encode(pidlab::lcmt_control_command{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_disturbance_request>(Encode(pidlab::lcmt_disturbance_request{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_disturbance_sample>(Encode(pidlab::lcmt_disturbance_sample{})));
  EXPECT_TRUE(Ok<pidlab::lcmt_trajectory_request>(Encode(pidlab::lcmt_trajectory_request{})));
}

TEST(WireLayout, AnUnknownFingerprintFails) {
  const std::vector<uint8_t> buf = Encode(pidlab::lcmt_plant_output{});
  EXPECT_FALSE(WireLayoutOk(0x0123456789abcdefLL, buf.data(), static_cast<int>(buf.size())));
}

TEST(WireLayout, APayloadShorterThanTheHeaderFails) {
  std::vector<uint8_t> buf = Encode(pidlab::lcmt_plant_output{});
  buf.resize(kBody - 1);
  EXPECT_FALSE(Ok<pidlab::lcmt_plant_output>(buf));
}

TEST(WireLayout, AnArrayCutShortFailsAtEveryLength) {
  const std::vector<uint8_t> full = Encode(Chunk(4));
  for (std::size_t size = kBody; size < full.size(); ++size) {
    const std::vector<uint8_t> cut(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(size));
    EXPECT_FALSE(Ok<pidlab::lcmt_trajectory_chunk>(cut)) << size << " of " << full.size() << " bytes";
  }
}

TEST(WireLayout, AnArrayLengthBeyondTheBytesPresentFails) {
  std::vector<uint8_t> buf = Encode(Chunk(4));
  PutInt32(&buf, kBody, 5);
  EXPECT_FALSE(Ok<pidlab::lcmt_trajectory_chunk>(buf));
  PutInt32(&buf, kBody, 1 << 28);  // what made LCM 1.3.1's decoder zero-fill gigabytes
  EXPECT_FALSE(Ok<pidlab::lcmt_trajectory_chunk>(buf));
  PutInt32(&buf, kBody, -1);
  EXPECT_FALSE(Ok<pidlab::lcmt_trajectory_chunk>(buf));
}

TEST(WireLayout, AnArrayOverTheProtocolsLimitFailsEvenWhenTheBytesArePresent) {
  EXPECT_TRUE(Ok<pidlab::lcmt_trajectory_chunk>(Encode(Chunk(static_cast<int>(kMaxTrajectoryChunk)))));
  EXPECT_FALSE(Ok<pidlab::lcmt_trajectory_chunk>(Encode(Chunk(static_cast<int>(kMaxTrajectoryChunk) + 1))));
  pidlab::lcmt_episode_config config{};
  config.num_size = kMaxPolynomialCoefficients + 1;
  config.num.assign(static_cast<std::size_t>(config.num_size), 1.0);
  EXPECT_FALSE(Ok<pidlab::lcmt_episode_config>(Encode(config)));
  config.num_size = kMaxPolynomialCoefficients;
  config.num.resize(static_cast<std::size_t>(config.num_size));
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_config>(Encode(config)));
}

TEST(WireLayout, AStringWithoutItsNulOrLongerThanThePayloadFails) {
  pidlab::lcmt_ready ready{};
  ready.role = "plant";
  const int role_at = kBody + 1;  // after int8_t state
  std::vector<uint8_t> buf = Encode(ready);
  ASSERT_TRUE(Ok<pidlab::lcmt_ready>(buf));
  std::vector<uint8_t> no_nul = buf;
  no_nul[static_cast<std::size_t>(role_at + 4 + 5)] = 'x';  // "plant" then its NUL
  EXPECT_FALSE(Ok<pidlab::lcmt_ready>(no_nul));
  std::vector<uint8_t> long_string = buf;
  PutInt32(&long_string, role_at, static_cast<int32_t>(buf.size()));
  EXPECT_FALSE(Ok<pidlab::lcmt_ready>(long_string));
  std::vector<uint8_t> empty = buf;
  PutInt32(&empty, role_at, 0);  // LCM strings always hold at least the NUL
  EXPECT_FALSE(Ok<pidlab::lcmt_ready>(empty));
}

TEST(WireLayout, AStringOverTheLimitFails) {
  pidlab::lcmt_episode_summary summary{};
  summary.message = std::string(static_cast<std::size_t>(kMaxStringBytes) - 1, 'm');
  EXPECT_TRUE(Ok<pidlab::lcmt_episode_summary>(Encode(summary)));
  summary.message += 'm';
  EXPECT_FALSE(Ok<pidlab::lcmt_episode_summary>(Encode(summary)));
}

TEST(EscapeWireText, EscapesEverythingOutsidePrintableAsciiAndTheBackslash) {
  EXPECT_EQ(EscapeWireText("PIDLAB_CONTROL"), "PIDLAB_CONTROL");
  EXPECT_EQ(EscapeWireText(std::string("a\\b\0c", 5)), "a\\x5cb\\x00c");
  EXPECT_EQ(EscapeWireText("\x7f\x80"), "\\x7f\\x80");
}

TEST(EscapeWireText, CutsAtMaxBytesAndSaysSo) {
  EXPECT_EQ(EscapeWireText("abcdef", 3), "abc...");
  EXPECT_EQ(EscapeWireText("abc", 3), "abc");
  EXPECT_EQ(EscapeWireText("\x01\x02", 4), "\\x01...");
}

}  // namespace
}  // namespace pidlab::transport
