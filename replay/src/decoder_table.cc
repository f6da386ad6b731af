#include "pidlab/replay/decoder_table.h"

#include <climits>
#include <exception>

namespace pidlab::replay {
namespace {

// Walks the wire layout of a message field by field: any string or array
// whose declared length does not fit in the bytes left makes it bad.
class LayoutCheck {
 public:
  LayoutCheck(const uint8_t* data, std::size_t size) : data_(data), size_(size), ok_(size >= 8) {}
  LayoutCheck& Fixed(std::size_t bytes) {
    if (ok_ && size_ - pos_ >= bytes)
      pos_ += bytes;
    else
      ok_ = false;
    return *this;
  }
  /// An int32 length (with the terminating NUL) and the bytes.
  LayoutCheck& String() {
    int32_t len = 0;
    if (!ReadInt32(&len) || len < 1 || static_cast<std::size_t>(len) > size_ - pos_ ||
        data_[pos_ + static_cast<std::size_t>(len) - 1] != 0)
      ok_ = false;
    else
      pos_ += static_cast<std::size_t>(len);
    return *this;
  }
  /// An int32 element count followed by count * element_bytes (several arrays
  /// of the same count: element_bytes is their sum).
  LayoutCheck& Array(std::size_t element_bytes) {
    int32_t count = 0;
    if (!ReadInt32(&count) || count < 0 || static_cast<std::size_t>(count) > (size_ - pos_) / element_bytes)
      ok_ = false;
    else
      pos_ += static_cast<std::size_t>(count) * element_bytes;
    return *this;
  }
  bool ok() const { return ok_; }

 private:
  bool ReadInt32(int32_t* v) {
    if (!ok_ || size_ - pos_ < 4) return false;
    const uint8_t* p = data_ + pos_;
    *v = static_cast<int32_t>((uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3]);
    pos_ += 4;
    return true;
  }
  const uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 8;  // after the fingerprint
  bool ok_;
};

constexpr std::size_t kHeader = 24;  // utime, episode_id, step

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
  LayoutCheck c(data, size);
  c.Fixed(kHeader);
  if (fingerprint == pidlab::lcmt_episode_config::getHash()) {
    c.String()
        .Array(8)
        .Array(8)
        .Fixed(7 * 8)
        .String()
        .Fixed(8)
        .String()
        .String()
        .Fixed(4 * 8)
        .String()
        .Fixed(6 * 8)
        .Fixed(2 * 8);
  } else if (fingerprint == pidlab::lcmt_ready::getHash()) {
    c.Fixed(1).String().Fixed(4).String();
  } else if (fingerprint == pidlab::lcmt_episode_summary::getHash()) {
    c.Fixed(1).Fixed(8).Fixed(8).String().String();
  } else if (fingerprint == pidlab::lcmt_trajectory_chunk::getHash()) {
    c.Array(3 * 8);
  } else if (fingerprint == pidlab::lcmt_disturbance_block::getHash()) {
    c.Fixed(8).Array(8);
  } else if (fingerprint != pidlab::lcmt_plant_output::getHash() &&
             fingerprint != pidlab::lcmt_control_command::getHash() &&
             fingerprint != pidlab::lcmt_disturbance_sample::getHash() &&
             fingerprint != pidlab::lcmt_disturbance_request::getHash() &&
             fingerprint != pidlab::lcmt_trajectory_request::getHash()) {
    return false;
  }
  return c.ok();
}

}  // namespace pidlab::replay
