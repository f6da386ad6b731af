#pragma once
// Reading pidlab episodes back from an LCM log (lcm-logger's file format).
//
// Messages are recognised by their LCM fingerprint, not by channel name, so a
// log of several trios with different channel prefixes, or one with foreign
// traffic, is read correctly; an episode is identified by (channel prefix,
// episode id). Everything a real log may hold is counted, never fatal: other
// channels, LCM self-test events, unknown or changed types on pidlab
// channels, undecodable payloads, data of an episode whose configuration is
// not in the log, a cut-off or corrupt tail.
//
// Pure library: no printing, no global state. Notes for the user are returned
// as one-line strings. ReadLog composes three pieces with headers of their
// own: EventReader (event_reader.h: lcm-logger's format, lengths checked
// before anything is allocated), DecoderTable (decoder_table.h: fingerprint
// -> type and a decoder that bounds every array first) and EpisodeAssembler
// (episode_assembler.h: episodes sized by their configuration only).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"
#include "pidlab/transport/auth.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/pacing.h"

namespace pidlab::replay {

/// How completely one message stream (plant outputs, commands or
/// disturbance samples) of an episode was recorded.
struct StreamStats {
  long expected = 0;            // steps the episode should have on this stream
  long received = 0;            // distinct steps present
  long duplicates = 0;          // repeats of a step with bit-identical content (retransmissions)
  long conflicts = 0;           // repeats of a step with different content (the first is kept)
  long out_of_order = 0;        // first arrivals of a step below one already seen
  long beyond_end = 0;          // steps outside 0..total_steps, ignored (see episode_assembler.h)
  long filled_from_chunks = 0;  // missing steps filled from the plant's trajectory chunks
  /// Missing steps as inclusive ranges [first, last] (after filling).
  std::vector<std::pair<long, long>> missing;
  long MissingCount() const;
};

struct Episode {
  std::string prefix;  // channel prefix, e.g. "PIDLAB_"
  int64_t episode_id = 0;
  bool has_config = false;
  /// The configuration is not in the log: it came from
  /// ReadOptions::supplied_configs.
  bool config_supplied = false;
  std::string config_error;  // set if a config was logged but is invalid
  transport::EpisodeSpec spec;
  /// The configuration as logged (its first copy), valid or not; meaningful
  /// when has_config or config_error is set.
  lcmt_episode_config config;
  /// The configuration's total_steps; without a valid configuration, the
  /// highest step logged within 0..transport::kMaxEpisodeSteps (listing only).
  long total_steps = 0;
  /// Per step k = 0..total_steps (u, n, status: 0..total_steps-1 used); empty
  /// for an episode without a valid configuration (never sized by a message).
  std::vector<double> y, u, n;
  std::vector<double> u_input_y;  // the y each command says it was computed from
  std::vector<int> status;        // command status, -1 if unknown
  std::vector<char> has_y, has_u, has_n;
  StreamStats outputs, commands, disturbances;
  bool has_summary = false;
  int summary_status = -1;  // lcmt_episode_summary::OK / FAILED
  long summary_step = 0;
  std::string summary_message;
  /// The pacing statistics of the SUMMARY (unpaced: factor 0).
  transport::RealtimeStats realtime;

  /// Config present and valid, every y of 0..total_steps, every u and n of
  /// 0..total_steps-1.
  bool Complete() const;
  /// One line: what is missing or wrong, empty if Complete().
  std::string CompletenessNote() const;
};

struct ReadOptions {
  /// Only this channel prefix (empty: every prefix).
  std::string channel_prefix;
  /// The trio's key (`--auth-key`): a message is used only if its tag
  /// verifies; untagged and badly tagged ones are counted as unauthenticated.
  /// Without a key, tagged messages are used unverified (and counted).
  std::optional<transport::AuthKey> auth_key;
  /// Configurations known from elsewhere (`pidlab launch --log` keeps a copy
  /// of each one it heard), on channel_prefix: each is used for its episode
  /// as if it had been logged after every event, unless the log holds a
  /// configuration of that episode itself (valid or not). The episode is
  /// then listed even if the log holds nothing else of it.
  std::vector<lcmt_episode_config> supplied_configs;
};

struct LogContents {
  long events = 0;           // events read from the file
  long pidlab_messages = 0;  // decoded pidlab messages
  long self_test = 0;        // LCM_SELF_TEST events
  long foreign = 0;          // other channels, unknown fingerprints
  long unknown_type = 0;     // unknown fingerprint on a channel named like a pidlab one (changed type?)
  long decode_failures = 0;  // known fingerprint, payload does not decode
  long other_prefix = 0;     // pidlab messages skipped by ReadOptions::channel_prefix
  long orphan_messages = 0;  // episode data without a configuration in the log
  long unauthenticated = 0;  // with a key: messages without a valid tag, dropped
  long unverified = 0;       // without a key: tagged messages used without checking their tag
  long eventnum_gaps = 0;    // jumps in the logger's event counter (events lost or corrupted)
  bool clean_end = true;     // the whole file was read
  bool opened = false;       // the file was opened (a false ReadLog then means: no LCM event in it)
  long long bytes_read = 0, file_bytes = 0;
  /// One line per notable thing (grouped: at most a few lines per kind).
  std::vector<std::string> notes;
  /// Episodes in order of first appearance.
  std::vector<Episode> episodes;
};

/// Reads the log at `path`. A failed Status only if the file cannot be
/// opened (kIoFailed), or holds no LCM event at all, an empty file included
/// (kInvalidInput; then contents->opened and contents->events == 0);
/// anything wrong inside a readable log is reported in *contents.
Status ReadLog(const std::string& path, const ReadOptions& options, LogContents* contents);

}  // namespace pidlab::replay
