#include "pidlab/replay/decoder_table.h"

#include <climits>
#include <exception>
#include <pidlab/lcmt_episode_config_layout.hpp>
#include <vector>

#include "pidlab/transport/wire.h"

namespace pidlab::replay {
namespace {

template <typename Msg>
bool DecodeAs(const uint8_t* data, std::size_t size, Msg* m) {
  if (size > INT_MAX || !PayloadLayoutOk(Msg::getHash(), data, size)) return false;
  try {
    if (m->decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return false;
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

template <typename Msg>
bool Decode(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  Msg m{};
  if (!DecodeAs(data, size, &m)) return false;
  *message = std::move(m);
  return true;
}

// The encoding of the fields appended to lcmt_episode_config after the
// frozen copy Old (generated from its "//@frozen" lines: Old's fields are the
// current type's first ones), at their defaults: 0, "", and the 1-DOF PID's
// setpoint weights b = c = 1. A default message encodes its strings and
// arrays empty, so the current type's bytes past Old's are exactly these.
template <typename Old>
const std::vector<uint8_t>& AppendedDefaults() {
  static const std::vector<uint8_t> tail = [] {
    pidlab::lcmt_episode_config now{};
    now.setpoint_weight_b = now.setpoint_weight_c = 1.0;
    std::vector<uint8_t> bytes(static_cast<std::size_t>(now.getEncodedSize()));
    now.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    const Old old{};
    return std::vector<uint8_t>(bytes.begin() + old.getEncodedSize(), bytes.end());
  }();
  return tail;
}

// A configuration of a log written before fields were appended (Old, one of
// the frozen copies): its layout checked with its own fingerprint, then read
// as the current type, the payload after the fingerprint followed by the
// appended fields' defaults (AppendedDefaults). Before the setpoint weights
// the PID was 1-DOF, its derivative on the measurement being c = 0.
template <typename Old>
bool DecodeFrozenConfig(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  if (size > INT_MAX || !PayloadLayoutOk(Old::getHash(), data, size)) return false;
  const std::vector<uint8_t>& tail = AppendedDefaults<Old>();
  std::vector<uint8_t> bytes(data, data + size);
  const uint64_t hash = static_cast<uint64_t>(pidlab::lcmt_episode_config::getHash());
  for (int i = 0; i < 8; ++i) bytes[static_cast<std::size_t>(i)] = static_cast<uint8_t>(hash >> (56 - 8 * i));
  bytes.insert(bytes.end(), tail.begin(), tail.end());
  pidlab::lcmt_episode_config m{};
  if (!DecodeAs(bytes.data(), bytes.size(), &m)) return false;
  m.setpoint_weight_c = m.derivative_on == "measurement" ? 0.0 : 1.0;
  *message = std::move(m);
  return true;
}

template <typename Msg>
MessageType Type(const char* name, const char* channel_suffix) {
  return MessageType{name, channel_suffix, Msg::getHash(), &Decode<Msg>};
}

template <typename Old>
MessageType Frozen() {
  return MessageType{"lcmt_episode_config", "EPISODE_CONFIG", Old::getHash(), &DecodeFrozenConfig<Old>};
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string MessageType::PrefixOf(const std::string& channel) const {
  return EndsWith(channel, channel_suffix) ? channel.substr(0, channel.size() - channel_suffix.size())
                                           : channel + "/";
}

DecoderTable::DecoderTable()
    : types_{
          Type<pidlab::lcmt_episode_config>("lcmt_episode_config", "EPISODE_CONFIG"),
// Every frozen copy of the configuration (generated from the .lcm file's
// "//@frozen" lines): logs written before an append.
#define PIDLAB_FROZEN_CONFIG(T) Frozen<pidlab::T>(),
          PIDLAB_lcmt_episode_config_FROZEN(PIDLAB_FROZEN_CONFIG)
#undef PIDLAB_FROZEN_CONFIG
              Type<pidlab::lcmt_ready>("lcmt_ready", "READY"),
          Type<pidlab::lcmt_plant_output>("lcmt_plant_output", "PLANT_OUTPUT"),
          Type<pidlab::lcmt_control_command>("lcmt_control_command", "CONTROL"),
          Type<pidlab::lcmt_disturbance_sample>("lcmt_disturbance_sample", "DISTURBANCE"),  // older logs
          Type<pidlab::lcmt_disturbance_block>("lcmt_disturbance_block", "DISTURBANCE_BLOCK"),
          Type<pidlab::lcmt_disturbance_request>("lcmt_disturbance_request", "DISTURBANCE_REQUEST"),
          Type<pidlab::lcmt_episode_summary>("lcmt_episode_summary", "SUMMARY"),
          Type<pidlab::lcmt_trajectory_request>("lcmt_trajectory_request", "TRAJECTORY_REQUEST"),
          Type<pidlab::lcmt_trajectory_chunk>("lcmt_trajectory_chunk", "TRAJECTORY"),
          Type<pidlab::lcmt_pacing_progress>("lcmt_pacing_progress",
                                             "PACING"),  // live figures: the SUMMARY's are final
          Type<pidlab::lcmt_tune_progress>("lcmt_tune_progress", "TUNE_PROGRESS"),  // a tuning's progress
      } {
}

const MessageType* DecoderTable::Find(int64_t fingerprint) const {
  for (const MessageType& t : types_)
    if (t.fingerprint == fingerprint) return &t;
  return nullptr;
}

bool DecoderTable::NamedLikePidlab(const std::string& channel) const {
  for (const MessageType& t : types_)
    if (EndsWith(channel, t.channel_suffix)) return true;
  return false;
}

bool DecoderTable::Fingerprint(const uint8_t* data, std::size_t size, int64_t* fingerprint) {
  if (size < 8) return false;
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | data[i];
  *fingerprint = static_cast<int64_t>(h);
  return true;
}

bool PayloadLayoutOk(int64_t fingerprint, const uint8_t* data, std::size_t size) {
  // The transport's check: the same layouts, and the protocol's limits.
  return size <= INT_MAX && transport::WireLayoutOk(fingerprint, data, static_cast<int>(size));
}

}  // namespace pidlab::replay
