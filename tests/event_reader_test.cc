// The three pieces of the log reader on their own: the event reader on files
// written byte by byte (garbage, absurd lengths, cut tails, extreme event
// numbers), the decoder table on hostile payloads, and the episode assembler
// on messages that claim absurd steps. The tests that must not allocate what
// a hostile length or step claims watch every allocation of this binary.

#include "pidlab/replay/event_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <new>
#include <pidlab/lcmt_episode_config_layout.hpp>
#include <pidlab/lcmt_episode_config_v1.hpp>
#include <pidlab/lcmt_episode_config_v2.hpp>
#include <pidlab/lcmt_episode_config_v3.hpp>
#include <pidlab/lcmt_episode_config_v4.hpp>
#include <pidlab/lcmt_episode_config_v5.hpp>
#include <pidlab/lcmt_episode_config_v6.hpp>
#include <pidlab/lcmt_ready.hpp>

#include "pidlab/replay/decoder_table.h"
#include "pidlab/replay/episode_assembler.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/wire.h"
#include "test_status.h"

namespace {
std::atomic<bool> g_watching{false};
std::atomic<std::size_t> g_largest{0}, g_total{0};
}  // namespace

// Every allocation of this binary goes through here (counted while watched).
void* operator new(std::size_t n) {
  if (g_watching.load(std::memory_order_relaxed)) {
    g_total += n;
    for (std::size_t seen = g_largest.load(); n > seen && !g_largest.compare_exchange_weak(seen, n);) {
    }
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
// Out of line, so that the compiler does not pair the free with a call of
// the (replaced) operator new and warn of a mismatch.
namespace {
[[gnu::noinline]] void Release(void* p) noexcept { std::free(p); }
}  // namespace
void operator delete(void* p) noexcept { Release(p); }
void operator delete[](void* p) noexcept { Release(p); }
void operator delete(void* p, std::size_t) noexcept { Release(p); }
void operator delete[](void* p, std::size_t) noexcept { Release(p); }

namespace pidlab::replay {
namespace {

namespace fs = std::filesystem;

// The largest single allocation and the total allocated while alive.
class AllocationWatch {
 public:
  AllocationWatch() {
    g_largest = 0;
    g_total = 0;
    g_watching = true;
  }
  ~AllocationWatch() { g_watching = false; }
  std::size_t largest() const { return g_largest; }
  std::size_t total() const { return g_total; }
};

constexpr std::size_t kMiB = 1024 * 1024;

void PutBigEndian(uint64_t v, int bytes, std::vector<uint8_t>* out) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// An event as lcm-logger writes it; the lengths in the header can lie.
std::vector<uint8_t> EventBytes(int64_t eventnum, const std::string& channel,
                                const std::vector<uint8_t>& data, int64_t channel_length = -1,
                                int64_t data_length = -1) {
  std::vector<uint8_t> b;
  PutBigEndian(EventReader::kSyncWord, 4, &b);
  PutBigEndian(static_cast<uint64_t>(eventnum), 8, &b);
  PutBigEndian(1700000000000000u, 8, &b);
  PutBigEndian(static_cast<uint64_t>(channel_length >= 0 ? channel_length : channel.size()), 4, &b);
  PutBigEndian(static_cast<uint64_t>(data_length >= 0 ? data_length : data.size()), 4, &b);
  b.insert(b.end(), channel.begin(), channel.end());
  b.insert(b.end(), data.begin(), data.end());
  return b;
}

class EventReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pidlab_event_reader_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "run.lcmlog").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes the pieces one after the other; returns the offset of each.
  std::vector<long long> Write(const std::vector<std::vector<uint8_t>>& pieces) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    std::vector<long long> offsets;
    long long at = 0;
    for (const auto& p : pieces) {
      offsets.push_back(at);
      out.write(reinterpret_cast<const char*>(p.data()), static_cast<std::streamsize>(p.size()));
      at += static_cast<long long>(p.size());
    }
    return offsets;
  }

  // Every event of the file; skipped stretches in *skipped.
  std::vector<LogEvent> ReadAll(EventReader* reader, std::vector<SkippedBytes>* skipped = nullptr) {
    std::string error;
    EXPECT_TRUE(IsOk(reader->Open(path_)));
    if (skipped) reader->OnSkip([skipped](const SkippedBytes& s) { skipped->push_back(s); });
    std::vector<LogEvent> events;
    for (LogEvent ev; reader->Next(&ev);) events.push_back(ev);
    return events;
  }

  fs::path dir_;
  std::string path_;
};

TEST_F(EventReaderTest, ReadsEveryEventThatLiblcmWrote) {
  {
    lcm::LogFile log(path_, "w");
    for (int i = 0; i < 3; ++i) {
      std::vector<uint8_t> data(static_cast<std::size_t>(10 * i), static_cast<uint8_t>(i));
      lcm::LogEvent ev;
      ev.timestamp = 1000 + i;
      ev.channel = "CHANNEL_" + std::to_string(i);
      ev.datalen = static_cast<int32_t>(data.size());
      ev.data = data.data();
      ASSERT_EQ(log.writeEvent(&ev), 0);
    }
  }
  EventReader reader;
  const std::vector<LogEvent> events = ReadAll(&reader);
  ASSERT_EQ(events.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const LogEvent& ev = events[static_cast<std::size_t>(i)];
    EXPECT_EQ(ev.eventnum, i);
    EXPECT_EQ(ev.timestamp, 1000 + i);
    EXPECT_EQ(ev.channel, "CHANNEL_" + std::to_string(i));
    EXPECT_EQ(ev.data, std::vector<uint8_t>(static_cast<std::size_t>(10 * i), static_cast<uint8_t>(i)));
  }
  EXPECT_EQ(events[1].offset, 28 + 9);
  EXPECT_TRUE(reader.clean());
  EXPECT_EQ(reader.events(), 3);
  EXPECT_EQ(reader.eventnum_gaps(), 0);
  EXPECT_EQ(reader.bytes_read(), reader.file_bytes());
}

TEST_F(EventReaderTest, ResyncsAfterGarbageBetweenEvents) {
  // The garbage holds the first three bytes of a sync word, to be scanned past.
  const std::vector<uint8_t> junk = {0x5a, 0xed, 0xa1, 0xda, 0x5a, 0x00, 0x01, 0x02, 0x03};
  const auto at = Write({EventBytes(0, "A", {1, 2, 3}), junk, EventBytes(1, "B", {4, 5})});
  EventReader reader;
  std::vector<SkippedBytes> skipped;
  const std::vector<LogEvent> events = ReadAll(&reader, &skipped);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].channel, "A");
  EXPECT_EQ(events[1].channel, "B");
  EXPECT_EQ(events[1].data, (std::vector<uint8_t>{4, 5}));
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0].kind, SkippedBytes::Kind::kGarbage);
  EXPECT_EQ(skipped[0].from, at[1]);
  EXPECT_EQ(skipped[0].to, at[2]);
  EXPECT_EQ(reader.skipped_stretches(), 1);
  EXPECT_EQ(reader.skipped_bytes(), static_cast<long long>(junk.size()));
  EXPECT_FALSE(reader.has_tail());
  EXPECT_FALSE(reader.clean());
  EXPECT_EQ(reader.bytes_read(), reader.file_bytes());
}

TEST_F(EventReaderTest, SkipsAnEventWithADataLengthOf0x7fffffffWithoutAllocatingIt) {
  const auto at =
      Write({EventBytes(0, "A", {1}), EventBytes(1, "HUGE", std::vector<uint8_t>(100, 7), -1, 0x7fffffff),
             EventBytes(2, "B", {2})});
  EventReader reader;
  std::vector<SkippedBytes> skipped;
  std::vector<LogEvent> events;
  std::size_t largest = 0;
  {
    const AllocationWatch watch;
    events = ReadAll(&reader, &skipped);
    largest = watch.largest();
  }
  EXPECT_LT(largest, kMiB) << "an allocation of " << largest << " bytes";
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].channel, "A");
  EXPECT_EQ(events[1].channel, "B");
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0].kind, SkippedBytes::Kind::kCorruptEvent);
  EXPECT_EQ(skipped[0].from, at[1]);
  EXPECT_EQ(skipped[0].to, at[2]);
  EXPECT_FALSE(reader.has_tail());
}

TEST_F(EventReaderTest, AFinalHeaderClaimingTwoGigabytesIsReportedAsTheTailNotAllocated) {
  const auto at = Write({EventBytes(0, "A", {1}), EventBytes(1, "HUGE", {1, 2, 3}, -1, 0x7fffffff)});
  EventReader reader;
  std::size_t largest = 0;
  std::vector<LogEvent> events;
  {
    const AllocationWatch watch;
    events = ReadAll(&reader);
    largest = watch.largest();
  }
  EXPECT_LT(largest, kMiB) << "an allocation of " << largest << " bytes";
  ASSERT_EQ(events.size(), 1u);
  EXPECT_TRUE(reader.has_tail());
  EXPECT_EQ(reader.tail_offset(), at[1]);
  EXPECT_EQ(reader.tail_bytes(), reader.file_bytes() - at[1]);
}

TEST_F(EventReaderTest, ACutOffLastEventIsReportedAsTheTailAndEverythingBeforeIsRead) {
  const auto at =
      Write({EventBytes(0, "A", {1}), EventBytes(1, "B", {2, 3}), EventBytes(2, "C", {4, 5, 6, 7})});
  fs::resize_file(path_, fs::file_size(path_) - 3);
  EventReader reader;
  std::vector<SkippedBytes> skipped;
  const std::vector<LogEvent> events = ReadAll(&reader, &skipped);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].channel, "B");
  EXPECT_TRUE(skipped.empty());
  EXPECT_TRUE(reader.has_tail());
  EXPECT_EQ(reader.tail_offset(), at[2]);
  EXPECT_EQ(reader.tail_bytes(), 28 + 1 + 4 - 3);
  EXPECT_EQ(reader.bytes_read(), at[2]);
  EXPECT_FALSE(reader.clean());
}

TEST_F(EventReaderTest, TrailingBytesWithoutASyncWordAreTheTail) {
  const auto at = Write({EventBytes(0, "A", {1}), {0x01, 0x02}});
  EventReader reader;
  const std::vector<LogEvent> events = ReadAll(&reader);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_TRUE(reader.has_tail());
  EXPECT_EQ(reader.tail_offset(), at[1]);
  EXPECT_EQ(reader.tail_bytes(), 2);
  EXPECT_EQ(reader.skipped_stretches(), 0);
}

TEST_F(EventReaderTest, ChannelLengthsOutsideOneTo256BytesAreNotEvents) {
  const std::string long_channel(EventReader::kMaxChannelBytes + 1, 'X');
  const auto at = Write({EventBytes(0, "", {1, 2}), EventBytes(1, long_channel, {3}),
                         EventBytes(2, std::string(EventReader::kMaxChannelBytes, 'Y'), {4})});
  EventReader reader;
  std::vector<SkippedBytes> skipped;
  const std::vector<LogEvent> events = ReadAll(&reader, &skipped);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].channel.size(), static_cast<std::size_t>(EventReader::kMaxChannelBytes));
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_EQ(skipped[0].from, at[0]);
  EXPECT_EQ(skipped[0].to, at[1]);
  EXPECT_EQ(skipped[1].from, at[1]);
  EXPECT_EQ(skipped[1].to, at[2]);
}

TEST_F(EventReaderTest, GarbageBeforeABrokenHeaderIsSkippedApartFromIt) {
  const auto at = Write(
      {EventBytes(0, "A", {1}), {9, 9, 9, 9, 9}, EventBytes(1, "BAD", {1}, 0, -1), EventBytes(2, "C", {2})});
  EventReader reader;
  std::vector<SkippedBytes> skipped;
  const std::vector<LogEvent> events = ReadAll(&reader, &skipped);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].channel, "C");
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_EQ(skipped[0].kind, SkippedBytes::Kind::kGarbage);
  EXPECT_EQ(skipped[0].from, at[1]);
  EXPECT_EQ(skipped[0].to, at[2]);
  EXPECT_EQ(skipped[1].kind, SkippedBytes::Kind::kCorruptEvent);
  EXPECT_EQ(skipped[1].from, at[2]);
  EXPECT_EQ(skipped[1].to, at[3]);
  EXPECT_EQ(reader.skipped_bytes(), at[3] - at[1]);
}

TEST_F(EventReaderTest, ReadsAnEventLargerThanItsReadBuffer) {
  std::vector<uint8_t> big(300 * 1024);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<uint8_t>(i * 7);
  Write({EventBytes(0, "A", {1}), EventBytes(1, "BIG", big), EventBytes(2, "C", {2})});
  EventReader reader;
  std::vector<LogEvent> events;
  std::size_t largest = 0;
  {
    const AllocationWatch watch;
    events = ReadAll(&reader);
    largest = watch.largest();
  }
  EXPECT_GE(largest, big.size());  // the watch sees what an event really needs
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[1].data, big);
  EXPECT_EQ(events[2].channel, "C");
  EXPECT_TRUE(reader.clean());
}

TEST_F(EventReaderTest, CountsEventnumGapsWithoutOverflowAtTheExtremes) {
  const int64_t max = std::numeric_limits<int64_t>::max(), min = std::numeric_limits<int64_t>::min();
  // max -> min is the counter wrapping (no gap); min -> 5, 5 -> 7 and 7 -> -1
  // are gaps; -1 -> 0 is not.
  Write({EventBytes(max, "A", {}), EventBytes(min, "A", {}), EventBytes(5, "A", {}), EventBytes(7, "A", {}),
         EventBytes(-1, "A", {}), EventBytes(0, "A", {})});
  EventReader reader;
  const std::vector<LogEvent> events = ReadAll(&reader);
  ASSERT_EQ(events.size(), 6u);
  EXPECT_EQ(events[0].eventnum, max);
  EXPECT_EQ(events[1].eventnum, min);
  EXPECT_EQ(reader.eventnum_gaps(), 3);
}

TEST_F(EventReaderTest, AnEmptyFileIsReadCleanlyWithNoEvents) {
  Write({});
  EventReader reader;
  EXPECT_TRUE(ReadAll(&reader).empty());
  EXPECT_TRUE(reader.clean());
  EXPECT_EQ(reader.file_bytes(), 0);
}

TEST_F(EventReaderTest, AMissingFileOrADirectoryCannotBeOpened) {
  std::string error;
  EventReader missing;
  EXPECT_FALSE(OkInto(missing.Open((dir_ / "missing.lcmlog").string()), &error));
  EXPECT_NE(error.find("cannot be read"), std::string::npos) << error;
  EventReader directory;
  EXPECT_FALSE(OkInto(directory.Open(dir_.string()), &error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
}

// ---- DecoderTable

template <typename Msg>
std::vector<uint8_t> Encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

TEST(DecoderTable, FindsEveryPidlabTypeByItsFingerprint) {
  const DecoderTable table;
  // Twelve types and the configurations of older logs (one per //@frozen line).
  namespace layout = pidlab::lcm_layout::lcmt_episode_config;
  ASSERT_EQ(table.types().size(), static_cast<std::size_t>(12 + layout::kVersions - 1));
  for (const MessageType& t : table.types()) {
    const MessageType* found = table.Find(t.fingerprint);
    ASSERT_NE(found, nullptr) << t.name;
    EXPECT_EQ(found->name, t.name);
  }
  EXPECT_EQ(table.Find(pidlab::lcmt_plant_output::getHash())->name, "lcmt_plant_output");
  EXPECT_EQ(table.Find(pidlab::lcmt_plant_output::getHash())->channel_suffix, "PLANT_OUTPUT");
  EXPECT_EQ(table.Find(0x0123456789abcdefLL), nullptr);
  int64_t fingerprint = 0;
  const uint8_t seven[7] = {};
  EXPECT_FALSE(DecoderTable::Fingerprint(seven, sizeof seven, &fingerprint));
}

TEST(DecoderTable, DecodesAWholeMessageAndRefusesMissingOrTrailingBytes) {
  pidlab::lcmt_plant_output y{};
  y.episode_id = 42;
  y.step = 17;
  y.y = 0.25;
  std::vector<uint8_t> bytes = Encode(y);
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_plant_output::getHash());
  ASSERT_NE(type, nullptr);
  PidlabMessage message;
  ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  const auto* decoded = std::get_if<pidlab::lcmt_plant_output>(&message);
  ASSERT_NE(decoded, nullptr);
  EXPECT_EQ(decoded->episode_id, 42);
  EXPECT_EQ(decoded->step, 17);
  EXPECT_EQ(decoded->y, 0.25);
  bytes.push_back(0);
  EXPECT_FALSE(type->decode(bytes.data(), bytes.size(), &message));
  bytes.resize(bytes.size() - 2);
  EXPECT_FALSE(type->decode(bytes.data(), bytes.size(), &message));
}

TEST(DecoderTable, AConfigurationOfAnOlderLogIsReadAsOneOfALinearPlant) {
  // lcmt_episode_config before the motor's fields were appended: its own
  // fingerprint, decoded with its own layout, read without a motor.
  pidlab::lcmt_episode_config_v1 old{};
  old.episode_id = 9;
  old.plant_name = "oscillator";
  old.num = {1.0};
  old.num_size = 1;
  old.den = {1.0, 0.0, 1.0};
  old.den_size = 3;
  old.kp = 3.0;
  old.anti_windup = "clamping";
  old.derivative_on = "error";
  old.integral = "backward-euler";
  old.disturbance_kind = "none";
  old.silence_deadline_s = 5.0;
  ASSERT_NE(pidlab::lcmt_episode_config_v1::getHash(), pidlab::lcmt_episode_config::getHash());
  std::vector<uint8_t> bytes = Encode(old);
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_episode_config_v1::getHash());
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->name, "lcmt_episode_config");
  EXPECT_EQ(type->channel_suffix, "EPISODE_CONFIG");
  PidlabMessage message;
  ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  const auto* config = std::get_if<pidlab::lcmt_episode_config>(&message);
  ASSERT_NE(config, nullptr);
  EXPECT_EQ(config->episode_id, 9);
  EXPECT_EQ(config->plant_name, "oscillator");
  EXPECT_EQ(config->den, old.den);
  EXPECT_EQ(config->kp, 3.0);
  EXPECT_EQ(config->silence_deadline_s, 5.0);
  EXPECT_EQ(config->motor_drive, "");
  EXPECT_EQ(config->motor_resistance_ohm, 0.0);
  // Its layout is checked like every other: a string running past the end.
  bytes[8 + 24] = 0x40;
  EXPECT_FALSE(type->decode(bytes.data(), bytes.size(), &message));
  // The new configuration cut inside the motor's fields is refused.
  pidlab::lcmt_episode_config now{};
  now.plant_name = now.anti_windup = now.derivative_on = now.integral = now.disturbance_kind = "x";
  now.motor_drive = "linear";
  std::vector<uint8_t> whole = Encode(now);
  const MessageType* current = table.Find(pidlab::lcmt_episode_config::getHash());
  ASSERT_NE(current, nullptr);
  EXPECT_TRUE(current->decode(whole.data(), whole.size(), &message));
  for (const std::size_t cut : {std::size_t{8}, std::size_t{8 + 7}, std::size_t{17 * 8}}) {
    const std::vector<uint8_t> cut_bytes(whole.begin(), whole.end() - static_cast<std::ptrdiff_t>(cut));
    EXPECT_FALSE(current->decode(cut_bytes.data(), cut_bytes.size(), &message)) << cut;
  }
  // motor_drive's length ("linear": 4 + 7 bytes, then the bytes of each
  // field after it: delay_s, the chirp's, the measurement noise's, the
  // setpoint weights', the relay's, ...): 2^31 - 1 + ...
  namespace layout = pidlab::lcm_layout::lcmt_episode_config;
  std::size_t after = 0;
  bool past = false;
  for (const layout::Field& f : layout::kFields) {
    // A string after it (controller_mode, "" here) is its length and its 0.
    if (past) after += f.kind == layout::WireField::kString ? 4 + 1 : 8;
    past = past || std::string(f.name) == "motor_drive";
  }
  whole[whole.size() - (4 + 7 + after)] = 0x7f;
  EXPECT_FALSE(current->decode(whole.data(), whole.size(), &message));
}

TEST(DecoderTable, AConfigurationWrittenBeforeTheDeadTimeIsReadWithoutADelay) {
  // lcmt_episode_config before delay_s was appended: its own fingerprint,
  // decoded with its own layout, the motor's fields kept, delay_s 0.
  pidlab::lcmt_episode_config_v2 old{};
  old.episode_id = 11;
  old.plant_name = "stepper_nonlinear";
  old.num = {1.0};
  old.num_size = 1;
  old.den = {1.0, 2.0, 1.0};
  old.den_size = 3;
  old.kp = 2.0;
  old.anti_windup = "clamping";
  old.derivative_on = "error";
  old.integral = "backward-euler";
  old.disturbance_kind = "none";
  old.motor_resistance_ohm = 33.0;
  old.motor_flux_linkage = 1.2e-3;
  old.motor_drive = "microstep";
  ASSERT_NE(pidlab::lcmt_episode_config_v2::getHash(), pidlab::lcmt_episode_config::getHash());
  ASSERT_NE(pidlab::lcmt_episode_config_v2::getHash(), pidlab::lcmt_episode_config_v1::getHash());
  std::vector<uint8_t> bytes = Encode(old);
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_episode_config_v2::getHash());
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->name, "lcmt_episode_config");
  PidlabMessage message;
  ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  const auto* config = std::get_if<pidlab::lcmt_episode_config>(&message);
  ASSERT_NE(config, nullptr);
  EXPECT_EQ(config->episode_id, 11);
  EXPECT_EQ(config->den, old.den);
  EXPECT_EQ(config->motor_resistance_ohm, 33.0);
  EXPECT_EQ(config->motor_flux_linkage, 1.2e-3);
  EXPECT_EQ(config->motor_drive, "microstep");
  EXPECT_EQ(config->delay_s, 0.0);
  // Cut inside the motor's fields: refused like every other layout.
  const std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 12);
  EXPECT_FALSE(type->decode(cut.data(), cut.size(), &message));
}

TEST(DecoderTable, AConfigurationWrittenBeforeTheChirpAndMeasurementNoiseIsReadWithoutThem) {
  // lcmt_episode_config before the chirp's band and the measurement noise
  // were appended: its own fingerprint and layout, the delay kept, the new
  // fields 0 (no chirp, no noise on y).
  pidlab::lcmt_episode_config_v3 old{};
  old.episode_id = 12;
  old.plant_name = "custom";
  old.num = {1.0};
  old.num_size = 1;
  old.den = {1.0, 1.0};
  old.den_size = 2;
  old.anti_windup = "clamping";
  old.derivative_on = "error";
  old.integral = "backward-euler";
  old.disturbance_kind = "prbs";
  old.seed = 5;
  old.delay_s = 0.3;
  ASSERT_NE(pidlab::lcmt_episode_config_v3::getHash(), pidlab::lcmt_episode_config::getHash());
  ASSERT_NE(pidlab::lcmt_episode_config_v3::getHash(), pidlab::lcmt_episode_config_v2::getHash());
  std::vector<uint8_t> bytes = Encode(old);
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_episode_config_v3::getHash());
  ASSERT_NE(type, nullptr);
  EXPECT_EQ(type->name, "lcmt_episode_config");
  PidlabMessage message;
  ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  const auto* config = std::get_if<pidlab::lcmt_episode_config>(&message);
  ASSERT_NE(config, nullptr);
  EXPECT_EQ(config->episode_id, 12);
  EXPECT_EQ(config->disturbance_kind, "prbs");
  EXPECT_EQ(config->seed, 5);
  EXPECT_EQ(config->delay_s, 0.3);
  EXPECT_EQ(config->chirp_f1_hz, 0.0);
  EXPECT_EQ(config->measurement_noise, 0.0);
  // Cut inside delay_s: refused like every other layout.
  const std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 4);
  EXPECT_FALSE(type->decode(cut.data(), cut.size(), &message));
}

TEST(DecoderTable, AConfigurationWrittenBeforeTheSetpointWeightsIsReadAsTheOneDofPid) {
  // lcmt_episode_config before the 2-DOF PID's setpoint weights were
  // appended: b = 1, and c = 1, or 0 for a derivative on the measurement.
  for (const std::string derivative_on : {"error", "measurement"}) {
    pidlab::lcmt_episode_config_v4 old{};
    old.episode_id = 13;
    old.plant_name = "custom";
    old.num = {1.0};
    old.num_size = 1;
    old.den = {1.0, 1.0};
    old.den_size = 2;
    old.anti_windup = "clamping";
    old.derivative_on = derivative_on;
    old.integral = "backward-euler";
    old.disturbance_kind = "chirp";
    old.chirp_f1_hz = 2.0;
    old.measurement_noise = 0.01;
    old.delay_s = 0.3;
    ASSERT_NE(pidlab::lcmt_episode_config_v4::getHash(), pidlab::lcmt_episode_config::getHash());
    ASSERT_NE(pidlab::lcmt_episode_config_v4::getHash(), pidlab::lcmt_episode_config_v3::getHash());
    std::vector<uint8_t> bytes = Encode(old);
    const DecoderTable table;
    const MessageType* type = table.Find(pidlab::lcmt_episode_config_v4::getHash());
    ASSERT_NE(type, nullptr);
    EXPECT_EQ(type->name, "lcmt_episode_config");
    PidlabMessage message;
    ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
    const auto* config = std::get_if<pidlab::lcmt_episode_config>(&message);
    ASSERT_NE(config, nullptr);
    EXPECT_EQ(config->episode_id, 13);
    EXPECT_EQ(config->delay_s, 0.3);
    EXPECT_EQ(config->chirp_f1_hz, 2.0);
    EXPECT_EQ(config->measurement_noise, 0.01);
    EXPECT_EQ(config->derivative_on, derivative_on);
    EXPECT_EQ(config->setpoint_weight_b, 1.0);
    EXPECT_EQ(config->setpoint_weight_c, derivative_on == "error" ? 1.0 : 0.0);
    // Cut inside the measurement noise's seed: refused like every other layout.
    const std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 4);
    EXPECT_FALSE(type->decode(cut.data(), cut.size(), &message));
  }
}

TEST(DecoderTable, EachGeneratedFrozenConfigurationKeepsTheFingerprintItsLogsCarry) {
  // The frozen copies are generated from lcmt_episode_config.lcm's
  // "//@frozen" lines; these are the fingerprints of the hand-written copies
  // they replaced, which every log written before an append carries.
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v1::getHash()), 0xfe4e3ce8f5a0287bULL);
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v2::getHash()), 0xdaafa1e58acc7835ULL);
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v3::getHash()), 0x7996f8fa958b6b63ULL);
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v4::getHash()), 0xab82a939990368c8ULL);
  // v5: the type before measurement_resolution (lcm-gen --python of that
  // .lcm file gives the same packed fingerprint).
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v5::getHash()), 0xae1743586efaa30bULL);
  // v6: the type before the relay autotune's fields (controller_mode, relay_*).
  EXPECT_EQ(static_cast<uint64_t>(pidlab::lcmt_episode_config_v6::getHash()), 0x60ba0c6d742c79c4ULL);
  EXPECT_EQ(transport::EpisodeConfigVersion(pidlab::lcmt_episode_config_v1::getHash()), 1);
  EXPECT_EQ(transport::EpisodeConfigVersion(pidlab::lcmt_episode_config_v4::getHash()), 4);
  EXPECT_EQ(transport::EpisodeConfigVersion(pidlab::lcmt_episode_config::getHash()),
            transport::kEpisodeConfigVersion);
  EXPECT_EQ(transport::EpisodeConfigVersion(pidlab::lcmt_ready::getHash()), 0);
}

TEST(DecoderTable, AnOlderConfigurationReadsAsTheCurrentOneWithOnlyTheAppendedFieldsAtTheirDefaults) {
  // Every field of the frozen copy keeps its value, whatever its version;
  // everything appended after it is 0 or "" (b = c = 1 for the 1-DOF PID).
  pidlab::lcmt_episode_config_v2 old{};
  old.utime = 11;
  old.episode_id = 7;
  old.plant_name = "stepper_nonlinear";
  old.num = {2.0};
  old.num_size = 1;
  old.den = {1.0, 3.0, 0.0};
  old.den_size = 3;
  old.kp = 1.5;
  old.ki = 0.25;
  old.kd = 0.125;
  old.reference = -2.0;
  old.derivative_filter_s = 0.01;
  old.output_min = -3.0;
  old.output_max = 4.0;
  old.anti_windup = "back-calculation";
  old.back_calculation_gain = 2.5;
  old.derivative_on = "measurement";
  old.integral = "trapezoidal";
  old.dt_s = 0.001;
  old.sample_time_s = 0.05;
  old.horizon_s = 1.0;
  old.total_steps = 1000;
  old.disturbance_kind = "square";
  old.disturbance_amplitude = 0.5;
  old.disturbance_period_s = 0.2;
  old.disturbance_phase_s = 0.05;
  old.disturbance_step_time_s = 0.3;
  old.noise_hold_s = 0.01;
  old.seed = 99;
  old.retransmit_interval_s = 0.004;
  old.silence_deadline_s = 6.0;
  old.motor_resistance_ohm = 1.1;
  old.motor_flux_linkage = 0.02;
  old.motor_rel_tolerance = 1e-9;
  old.motor_drive = "microstep";
  std::vector<uint8_t> bytes = Encode(old);
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_episode_config_v2::getHash());
  ASSERT_NE(type, nullptr);
  PidlabMessage message;
  ASSERT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  const auto* c = std::get_if<pidlab::lcmt_episode_config>(&message);
  ASSERT_NE(c, nullptr);
  pidlab::lcmt_episode_config want{};
  want.utime = 11;
  want.episode_id = 7;
  want.plant_name = old.plant_name;
  want.num_size = 1;
  want.num = old.num;
  want.den_size = 3;
  want.den = old.den;
  want.kp = 1.5;
  want.ki = 0.25;
  want.kd = 0.125;
  want.reference = -2.0;
  want.derivative_filter_s = 0.01;
  want.output_min = -3.0;
  want.output_max = 4.0;
  want.anti_windup = old.anti_windup;
  want.back_calculation_gain = 2.5;
  want.derivative_on = old.derivative_on;
  want.integral = old.integral;
  want.dt_s = 0.001;
  want.sample_time_s = 0.05;
  want.horizon_s = 1.0;
  want.total_steps = 1000;
  want.disturbance_kind = old.disturbance_kind;
  want.disturbance_amplitude = 0.5;
  want.disturbance_period_s = 0.2;
  want.disturbance_phase_s = 0.05;
  want.disturbance_step_time_s = 0.3;
  want.noise_hold_s = 0.01;
  want.seed = 99;
  want.retransmit_interval_s = 0.004;
  want.silence_deadline_s = 6.0;
  want.motor_resistance_ohm = 1.1;
  want.motor_flux_linkage = 0.02;
  want.motor_rel_tolerance = 1e-9;
  want.motor_drive = old.motor_drive;
  want.setpoint_weight_b = 1.0;
  want.setpoint_weight_c = 0.0;  // derivative on the measurement
  // The same message, byte for byte.
  EXPECT_EQ(Encode(*c), Encode(want));
}

TEST(DecoderTable, RefusesAnArrayLongerThanThePayloadBeforeTheDecoderAllocatesIt) {
  pidlab::lcmt_trajectory_chunk chunk{};
  chunk.count = 1;
  chunk.y = chunk.u = chunk.n = {1.0};
  std::vector<uint8_t> bytes = Encode(chunk);
  const std::size_t count_at = 8 + 24;
  const DecoderTable table;
  const MessageType* type = table.Find(pidlab::lcmt_trajectory_chunk::getHash());
  ASSERT_NE(type, nullptr);
  PidlabMessage message;
  EXPECT_TRUE(type->decode(bytes.data(), bytes.size(), &message));
  for (const uint8_t first : {uint8_t{0x7f}, uint8_t{0xff}}) {  // 2^31 - 1 + ..., and a negative count
    bytes[count_at] = first;
    std::size_t largest = 0;
    bool ok = true;
    {
      const AllocationWatch watch;
      ok = type->decode(bytes.data(), bytes.size(), &message);
      largest = watch.largest();
    }
    EXPECT_FALSE(ok);
    EXPECT_LT(largest, kMiB) << "an allocation of " << largest << " bytes";
    EXPECT_FALSE(PayloadLayoutOk(pidlab::lcmt_trajectory_chunk::getHash(), bytes.data(), bytes.size()));
  }
}

TEST(DecoderTable, AStringLongerThanThePayloadIsRefused) {
  pidlab::lcmt_episode_summary summary{};
  summary.message = "done";
  std::vector<uint8_t> bytes = Encode(summary);
  const std::size_t message_length_at = 8 + 24 + 1 + 8 + 8;
  EXPECT_TRUE(PayloadLayoutOk(pidlab::lcmt_episode_summary::getHash(), bytes.data(), bytes.size()));
  bytes[message_length_at] = 0x40;
  EXPECT_FALSE(PayloadLayoutOk(pidlab::lcmt_episode_summary::getHash(), bytes.data(), bytes.size()));
  EXPECT_FALSE(PayloadLayoutOk(0x0123456789abcdefLL, bytes.data(), bytes.size()));
}

TEST(DecoderTable, TheChannelPrefixIsTheChannelWithoutTheTypesSuffix) {
  const DecoderTable table;
  const MessageType& output = *table.Find(pidlab::lcmt_plant_output::getHash());
  const MessageType& chunk = *table.Find(pidlab::lcmt_trajectory_chunk::getHash());
  EXPECT_EQ(output.PrefixOf("LAB_A_PLANT_OUTPUT"), "LAB_A_");
  EXPECT_EQ(output.PrefixOf("PLANT_OUTPUT"), "");
  // The fingerprint decides the type; a chunk on a request channel is not
  // taken for the prefix "X_" of a chunk.
  EXPECT_EQ(chunk.PrefixOf("X_TRAJECTORY_REQUEST"), "X_TRAJECTORY_REQUEST/");
  EXPECT_TRUE(table.NamedLikePidlab("ANY_CONTROL"));
  EXPECT_FALSE(table.NamedLikePidlab("ROBOT_POSE"));
}

// ---- EpisodeAssembler

// A valid configuration of `steps` steps (dt 10 ms, double integrator).
pidlab::lcmt_episode_config Config(int64_t id, long steps) {
  transport::EpisodeSpec spec;
  std::string error;
  EXPECT_TRUE(IsOk(MakePlant("double_integrator", StepperMotorParameters{}, &spec.plant)));
  spec.episode_id = id;
  spec.gains = {2.0, 0.5, 1.5};
  spec.dt_s = spec.pid.dt_s = 0.01;
  spec.sample_time_s = 0.01;
  spec.horizon_s = 0.01 * static_cast<double>(steps);
  spec.total_steps = steps;
  EXPECT_TRUE(spec.IsValid(&error)) << error;
  return transport::MakeEpisodeConfig(spec);
}

pidlab::lcmt_plant_output Output(int64_t id, int64_t step, double y) {
  pidlab::lcmt_plant_output m{};
  m.episode_id = id;
  m.step = step;
  m.y = y;
  return m;
}

pidlab::lcmt_control_command Command(int64_t id, int64_t step, double u) {
  pidlab::lcmt_control_command m{};
  m.episode_id = id;
  m.step = step;
  m.u = u;
  return m;
}

pidlab::lcmt_disturbance_sample Sample(int64_t id, int64_t step, double n) {
  pidlab::lcmt_disturbance_sample m{};
  m.episode_id = id;
  m.step = step;
  m.n = n;
  return m;
}

// Every step of a `steps`-step episode, except those listed.
void AddSteps(EpisodeAssembler* a, int64_t id, long steps, long skip_output = -1) {
  for (long k = 0; k <= steps; ++k) {
    if (k != skip_output) a->Add("PIDLAB_", Output(id, k, 0.5 * static_cast<double>(k)));
    if (k == steps) break;
    a->Add("PIDLAB_", Command(id, k, -1.0 * static_cast<double>(k)));
    a->Add("PIDLAB_", Sample(id, k, 0.25));
  }
}

TEST(EpisodeAssembler, BuildsAnEpisodeSizedByItsConfiguration) {
  EpisodeAssembler assembler;
  assembler.Add("PIDLAB_", Config(7, 10));
  AddSteps(&assembler, 7, 10);
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 1u);
  const Episode& e = out.episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(e.total_steps, 10);
  ASSERT_EQ(e.y.size(), 11u);
  EXPECT_EQ(e.y[10], 5.0);
  EXPECT_EQ(e.u[9], -9.0);
  EXPECT_EQ(e.n[3], 0.25);
  EXPECT_EQ(e.outputs.received, 11);
  EXPECT_EQ(e.commands.expected, 10);
  EXPECT_TRUE(out.orphans.empty());
  EXPECT_TRUE(out.notes.empty());
}

TEST(EpisodeAssembler, AnOrphanAtStep2To40UsesNoMemoryForIt) {
  EpisodeAssembler assembler;
  AssembledEpisodes out;
  std::size_t largest = 0, total = 0;
  {
    const AllocationWatch watch;
    assembler.Add("PIDLAB_", Output(9, int64_t{1} << 40, 1.0));
    out = assembler.Finish();
    largest = watch.largest();
    total = watch.total();
  }
  EXPECT_LT(largest, 64 * 1024u) << "an allocation of " << largest << " bytes";
  EXPECT_LT(total, kMiB) << total << " bytes allocated";
  ASSERT_EQ(out.episodes.size(), 1u);
  const Episode& e = out.episodes[0];
  EXPECT_FALSE(e.has_config);
  EXPECT_TRUE(e.y.empty());
  EXPECT_TRUE(e.has_y.empty());
  EXPECT_EQ(e.total_steps, 0);
  EXPECT_EQ(e.outputs.beyond_end, 1);
  EXPECT_EQ(out.orphans, std::vector<std::string>{"PIDLAB_ episode 9"});
}

TEST(EpisodeAssembler, AnOrphanListsItsHighestStepWithoutPerStepVectors) {
  EpisodeAssembler assembler;
  AddSteps(&assembler, 3, 20, 12);
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 1u);
  const Episode& e = out.episodes[0];
  EXPECT_EQ(e.total_steps, 20);
  EXPECT_TRUE(e.y.empty());
  EXPECT_EQ(e.outputs.received, 20);
  ASSERT_EQ(e.outputs.missing.size(), 1u);
  EXPECT_EQ(e.outputs.missing[0], std::make_pair(12L, 12L));
  EXPECT_EQ(e.CompletenessNote(), "no episode configuration in the log");
}

TEST(EpisodeAssembler, StepsBeyondTheConfiguredEndAreCountedNotStored) {
  EpisodeAssembler assembler;
  assembler.Add("PIDLAB_", Config(7, 10));
  AddSteps(&assembler, 7, 10);
  assembler.Add("PIDLAB_", Output(7, 11, 1.0));
  assembler.Add("PIDLAB_", Output(7, int64_t{1} << 40, 1.0));
  assembler.Add("PIDLAB_", Output(7, -5, 1.0));
  assembler.Add("PIDLAB_", Command(7, 10, 1.0));  // commands end at step 9
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 1u);
  const Episode& e = out.episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(e.y.size(), 11u);
  EXPECT_EQ(e.outputs.beyond_end, 3);
  EXPECT_EQ(e.outputs.out_of_order, 0);
  EXPECT_EQ(e.commands.beyond_end, 1);
}

TEST(EpisodeAssembler, ADisturbanceBlockAtTheLargestStepDoesNotOverflow) {
  EpisodeAssembler assembler;
  assembler.Add("PIDLAB_", Config(7, 10));
  AddSteps(&assembler, 7, 10);
  pidlab::lcmt_disturbance_block block{};
  block.episode_id = 7;
  block.step = std::numeric_limits<int64_t>::max() - 1;
  block.dt_s = 0.01;
  block.count = 4;
  block.n = {1.0, 2.0, 3.0, 4.0};
  assembler.Add("PIDLAB_", block);
  pidlab::lcmt_trajectory_chunk chunk{};
  chunk.episode_id = 7;
  chunk.step = block.step;
  chunk.count = 4;
  chunk.y = chunk.u = chunk.n = block.n;
  assembler.Add("PIDLAB_", chunk);
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 1u);
  EXPECT_EQ(out.episodes[0].disturbances.beyond_end, 4);
  EXPECT_EQ(out.episodes[0].outputs.filled_from_chunks, 0);
  EXPECT_TRUE(out.episodes[0].Complete());
}

TEST(EpisodeAssembler, TrajectoryChunksFillOnlyTheMissingSteps) {
  EpisodeAssembler assembler;
  assembler.Add("PIDLAB_", Config(7, 10));
  AddSteps(&assembler, 7, 10, 3);
  pidlab::lcmt_trajectory_chunk chunk{};
  chunk.episode_id = 7;
  chunk.step = 2;
  chunk.count = 3;
  chunk.y = {100.0, 101.0, 102.0};
  chunk.u = {200.0, 201.0, 202.0};
  chunk.n = {300.0, 301.0, 302.0};
  assembler.Add("PIDLAB_", chunk);
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 1u);
  const Episode& e = out.episodes[0];
  EXPECT_TRUE(e.Complete()) << e.CompletenessNote();
  EXPECT_EQ(e.y[2], 1.0);    // logged
  EXPECT_EQ(e.y[3], 101.0);  // from the chunk
  EXPECT_EQ(e.outputs.filled_from_chunks, 1);
  EXPECT_EQ(e.commands.filled_from_chunks, 0);
}

TEST(EpisodeAssembler, AConfigurationRepeatedWithOtherContentIsNotedAndTheFirstKept) {
  EpisodeAssembler assembler;
  assembler.Add("PIDLAB_", Config(7, 10));
  pidlab::lcmt_episode_config again = Config(7, 10);
  again.utime = 12345;  // a resend: same content
  assembler.Add("PIDLAB_", again);
  assembler.Add("PIDLAB_", Config(8, 10));
  assembler.Add("PIDLAB_", Config(8, 20));
  const AssembledEpisodes out = assembler.Finish();
  ASSERT_EQ(out.episodes.size(), 2u);
  EXPECT_EQ(out.episodes[1].total_steps, 10);
  ASSERT_EQ(out.notes.size(), 1u);
  EXPECT_NE(out.notes[0].find("PIDLAB_ episode 8"), std::string::npos) << out.notes[0];
}

TEST(EpisodeAssembler, SummariesAndAcknowledgementsAloneAreNoEpisode) {
  EpisodeAssembler assembler;
  pidlab::lcmt_episode_summary summary{};
  summary.episode_id = 5;
  assembler.Add("PIDLAB_", summary);
  pidlab::lcmt_ready ready{};
  ready.episode_id = 5;
  assembler.Add("PIDLAB_", ready);
  EXPECT_TRUE(assembler.Finish().episodes.empty());
}

}  // namespace
}  // namespace pidlab::replay
