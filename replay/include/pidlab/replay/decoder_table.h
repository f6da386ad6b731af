#pragma once
// The pidlab message types a log may hold, by LCM fingerprint: each with its
// type name, its channel name without the prefix, and a decode function that
// checks the payload's layout before the generated decoder runs (the decoders
// of LCM 1.3.1 trust the string and array lengths declared in the message: a
// corrupt count of 2^30 would make them allocate gigabytes or read out of
// bounds).

#include <cstddef>
#include <cstdint>
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
#include <string>
#include <variant>
#include <vector>

namespace pidlab::replay {

/// One decoded pidlab message.
using PidlabMessage =
    std::variant<pidlab::lcmt_episode_config, pidlab::lcmt_ready, pidlab::lcmt_plant_output,
                 pidlab::lcmt_control_command, pidlab::lcmt_disturbance_sample,
                 pidlab::lcmt_disturbance_block, pidlab::lcmt_disturbance_request,
                 pidlab::lcmt_episode_summary, pidlab::lcmt_trajectory_request, pidlab::lcmt_trajectory_chunk,
                 pidlab::lcmt_pacing_progress, pidlab::lcmt_tune_progress>;

/// A pidlab message type.
struct MessageType {
  std::string name;            // "lcmt_plant_output"
  std::string channel_suffix;  // its channel without the prefix: "PLANT_OUTPUT"
  int64_t fingerprint = 0;
  /// Checks the layout (every string and array length within the payload),
  /// then decodes. True only if the whole payload is one message of this type.
  bool (*decode)(const uint8_t* data, std::size_t size, PidlabMessage* message) = nullptr;

  /// The channel prefix of `channel` carrying this type: the channel without
  /// the suffix, or the whole channel plus "/" on a channel not named like
  /// this type's (the fingerprint decides the type, the suffix the prefix).
  std::string PrefixOf(const std::string& channel) const;
};

class DecoderTable {
 public:
  /// Every pidlab message type.
  DecoderTable();

  /// The type with this fingerprint, nullptr if none.
  const MessageType* Find(int64_t fingerprint) const;
  /// True if `channel` ends like a pidlab channel (…PLANT_OUTPUT, …CONTROL, …).
  bool NamedLikePidlab(const std::string& channel) const;
  const std::vector<MessageType>& types() const { return types_; }

  /// The fingerprint (first 8 bytes, big-endian) of a payload; false if it
  /// is shorter than 8 bytes.
  static bool Fingerprint(const uint8_t* data, std::size_t size, int64_t* fingerprint);

 private:
  std::vector<MessageType> types_;
};

/// True if `data` has the wire layout of the pidlab type `fingerprint`: every
/// string and array it declares fits in the payload (no more bytes than
/// present, no negative count) and within the protocol's limits
/// (transport::WireLayoutOk, the live transport's own check). Types without
/// variable-length fields only need their fixed size (the decoder checks
/// it). False for an unknown type.
bool PayloadLayoutOk(int64_t fingerprint, const uint8_t* data, std::size_t size);

}  // namespace pidlab::replay
