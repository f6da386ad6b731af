#include "pidlab/replay/decoder_table.h"

#include "pidlab/transport/wire.h"

#include <climits>
#include <exception>

namespace pidlab::replay {
namespace {

template <typename Msg>
bool Decode(const uint8_t* data, std::size_t size, PidlabMessage* message) {
  if (size > INT_MAX || !PayloadLayoutOk(Msg::getHash(), data, size)) return false;
  Msg m{};
  try {
    if (m.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return false;
  } catch (const std::exception&) {
    return false;
  }
  *message = std::move(m);
  return true;
}

template <typename Msg>
MessageType Type(const char* name, const char* channel_suffix) {
  return MessageType{name, channel_suffix, Msg::getHash(), &Decode<Msg>};
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
          Type<pidlab::lcmt_ready>("lcmt_ready", "READY"),
          Type<pidlab::lcmt_plant_output>("lcmt_plant_output", "PLANT_OUTPUT"),
          Type<pidlab::lcmt_control_command>("lcmt_control_command", "CONTROL"),
          Type<pidlab::lcmt_disturbance_sample>("lcmt_disturbance_sample", "DISTURBANCE"),  // older logs
          Type<pidlab::lcmt_disturbance_block>("lcmt_disturbance_block", "DISTURBANCE_BLOCK"),
          Type<pidlab::lcmt_disturbance_request>("lcmt_disturbance_request", "DISTURBANCE_REQUEST"),
          Type<pidlab::lcmt_episode_summary>("lcmt_episode_summary", "SUMMARY"),
          Type<pidlab::lcmt_trajectory_request>("lcmt_trajectory_request", "TRAJECTORY_REQUEST"),
          Type<pidlab::lcmt_trajectory_chunk>("lcmt_trajectory_chunk", "TRAJECTORY"),
      } {}

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
