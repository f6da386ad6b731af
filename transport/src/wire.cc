#include "pidlab/transport/wire.h"

#include <cstdio>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_pacing_progress.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <pidlab/lcmt_tune_progress.hpp>

#include "pidlab/transport/protocol.h"

namespace pidlab::transport {
namespace {

// Walks the layout field by field; any field that does not fit, or a count
// beyond its limit, makes the whole message bad.
class LayoutCheck {
 public:
  LayoutCheck(const uint8_t* data, int size) : data_(data), size_(size) {}
  LayoutCheck& Fixed(int bytes) {
    if (ok_ && size_ - pos_ >= bytes)
      pos_ += bytes;
    else
      ok_ = false;
    return *this;
  }
  LayoutCheck& String() {
    int32_t len = 0;
    if (!ReadInt32(&len) || len < 1 || len > kMaxStringBytes || len > size_ - pos_ ||
        data_[pos_ + len - 1] != 0)
      ok_ = false;
    else
      pos_ += len;
    return *this;
  }
  /// An int32 element count (at most max_count) followed by count *
  /// element_bytes (several arrays of the same count: element_bytes is their sum).
  LayoutCheck& Array(int element_bytes, long max_count) {
    int32_t count = 0;
    if (!ReadInt32(&count) || count < 0 || count > max_count ||
        static_cast<long long>(count) * element_bytes > size_ - pos_)
      ok_ = false;
    else
      pos_ += count * element_bytes;
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
  int size_;
  int pos_ = 8;  // after the fingerprint
  bool ok_ = true;
};

constexpr int kHeader = 24;  // utime, episode_id, step

}  // namespace

int EpisodeConfigVersion(int64_t fingerprint) {
  const int64_t versions[kEpisodeConfigVersion] = {
#define PIDLAB_FINGERPRINT_OF(T) pidlab::T::getHash(),
      PIDLAB_lcmt_episode_config_FROZEN(PIDLAB_FINGERPRINT_OF)
#undef PIDLAB_FINGERPRINT_OF
          pidlab::lcmt_episode_config::getHash()};
  for (int v = 0; v < kEpisodeConfigVersion; ++v)
    if (versions[v] == fingerprint) return v + 1;
  return 0;
}

bool WireLayoutOk(int64_t fingerprint, const void* data, int size) {
  if (size < 8 + kHeader) return false;
  LayoutCheck c(static_cast<const uint8_t*>(data), size);
  c.Fixed(kHeader);
  // An episode configuration of any version: the fields of the .lcm file
  // (lcmt_episode_config_layout.hpp, generated from it) after the header,
  // as many as that version had.
  if (const int version = EpisodeConfigVersion(fingerprint); version > 0) {
    namespace layout = lcm_layout::lcmt_episode_config;
    for (int i = 3; i < layout::kFieldsInVersion[version - 1]; ++i) {
      const layout::Field& f = layout::kFields[i];
      if (f.kind == layout::WireField::kString)
        c.String();
      else if (f.kind == layout::WireField::kArray)
        c.Array(f.bytes, kMaxPolynomialCoefficients);  // num, den: the plant's polynomials
      else
        c.Fixed(f.bytes);
    }
  } else if (fingerprint == pidlab::lcmt_ready::getHash()) {
    c.Fixed(1).String().Fixed(4).String();
  } else if (fingerprint == pidlab::lcmt_episode_summary::getHash()) {
    c.Fixed(1).Fixed(8).Fixed(8).String().String().Fixed(6 * 8);
  } else if (fingerprint == pidlab::lcmt_trajectory_chunk::getHash()) {
    c.Array(3 * 8, kMaxTrajectoryChunk);
  } else if (fingerprint == pidlab::lcmt_tune_progress::getHash()) {
    c.Fixed(1 + 4 + 8 + 3 * 8 + 4).String().String();
  } else if (fingerprint == pidlab::lcmt_disturbance_block::getHash()) {
    c.Fixed(8).Array(8, kMaxNoiseRequest);
  } else if (fingerprint != pidlab::lcmt_plant_output::getHash() &&
             fingerprint != pidlab::lcmt_control_command::getHash() &&
             fingerprint != pidlab::lcmt_disturbance_request::getHash() &&
             fingerprint != pidlab::lcmt_disturbance_sample::getHash() &&
             fingerprint != pidlab::lcmt_trajectory_request::getHash() &&
             fingerprint != pidlab::lcmt_pacing_progress::getHash()) {
    return false;
  }
  return c.ok();
}

std::string EscapeWireText(const std::string& text, std::size_t max_bytes) {
  std::string out;
  for (unsigned char ch : text) {
    if (out.size() >= max_bytes) {
      out += "...";
      break;
    }
    if (ch >= 0x20 && ch < 0x7f && ch != '\\') {
      out += static_cast<char>(ch);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", ch);
      out += buf;
    }
  }
  return out;
}

}  // namespace pidlab::transport
