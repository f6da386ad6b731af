#include "pidlab/replay/log_reader.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

#include "pidlab/replay/decoder_table.h"
#include "pidlab/replay/episode_assembler.h"
#include "pidlab/replay/event_reader.h"

namespace pidlab::replay {
namespace {

// A count with a bounded list of examples for the notes.
struct Tally {
  long count = 0;
  std::set<std::string> examples;
  void Add(const std::string& example) {
    ++count;
    if (examples.size() < 4) examples.insert(example);
  }
  std::string Examples() const {
    std::string s;
    for (const auto& e : examples) s += (s.empty() ? "" : ", ") + e;
    return s;
  }
};

// What ReadLog counts while reading, besides LogContents' own counters.
struct Tallies {
  Tally foreign, unknown_type, decode_failed, other_prefix, orphans, unreadable;
};

std::string Ranges(const std::vector<std::pair<long, long>>& r) {
  std::ostringstream os;
  for (std::size_t i = 0; i < r.size() && i < 5; ++i) {
    if (i) os << ",";
    os << r[i].first;
    if (r[i].second != r[i].first) os << "-" << r[i].second;
  }
  if (r.size() > 5) os << ",...";
  return os.str();
}

std::string Describe(const SkippedBytes& s) {
  std::ostringstream os;
  if (s.kind == SkippedBytes::Kind::kGarbage)
    os << "bytes " << s.from << ".." << s.to - 1 << " between events are garbage; skipped";
  else
    os << "bytes " << s.from << ".." << s.to - 1 << " are not a readable event (corrupt); skipped";
  return os.str();
}

// An event whose payload is no pidlab message: counted by where it was.
void CountUnknown(const DecoderTable& table, const LogEvent& ev, Tallies* t) {
  int64_t fingerprint = 0;
  const bool has_fingerprint = DecoderTable::Fingerprint(ev.data.data(), ev.data.size(), &fingerprint);
  if (!table.NamedLikePidlab(ev.channel)) {
    t->foreign.Add(ev.channel);
  } else if (!has_fingerprint) {
    t->decode_failed.Add(ev.channel + " (" + std::to_string(ev.data.size()) +
                         " bytes: too short for a fingerprint)");
  } else {
    char buf[40];
    std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(fingerprint));
    t->unknown_type.Add(ev.channel + " (fingerprint " + std::string(buf) + ")");
  }
}

enum class Decoded { kOk, kUnverified, kUnauthenticated, kFailed };

// A message as the trio sent it: with a key, only a payload whose tag (the
// last 32 bytes) verifies; without one, a tagged payload is used unverified.
Decoded DecodeAuthenticated(const MessageType& type, const ReadOptions& options, const LogEvent& ev,
                            PidlabMessage* message) {
  const uint8_t* data = ev.data.data();
  const std::size_t size = ev.data.size();
  const bool tagged =
      size > transport::kAuthTagBytes && type.decode(data, size - transport::kAuthTagBytes, message);
  if (!options.auth_key) {
    if (tagged) return Decoded::kUnverified;
    return type.decode(data, size, message) ? Decoded::kOk : Decoded::kFailed;
  }
  if (!tagged) return type.decode(data, size, message) ? Decoded::kUnauthenticated : Decoded::kFailed;
  const std::size_t payload = size - transport::kAuthTagBytes;
  const auto tag = transport::AuthTag(*options.auth_key, ev.channel, data, payload);
  return std::equal(tag.begin(), tag.end(), data + payload) ? Decoded::kOk : Decoded::kUnauthenticated;
}

// One event: self-test, foreign, unknown, another prefix, undecodable, or a
// pidlab message for the assembler.
void HandleEvent(const DecoderTable& table, const ReadOptions& options, const LogEvent& ev,
                 EpisodeAssembler* assembler, Tallies* t, LogContents* out) {
  if (ev.channel == "LCM_SELF_TEST") {
    ++out->self_test;
    return;
  }
  int64_t fingerprint = 0;
  const MessageType* type = DecoderTable::Fingerprint(ev.data.data(), ev.data.size(), &fingerprint)
                                ? table.Find(fingerprint)
                                : nullptr;
  if (!type) {
    CountUnknown(table, ev, t);
    return;
  }
  const std::string prefix = type->PrefixOf(ev.channel);
  if (!options.channel_prefix.empty() && prefix != options.channel_prefix) {
    t->other_prefix.Add(prefix.empty() ? "(none)" : prefix);
    return;
  }
  PidlabMessage message;
  switch (DecodeAuthenticated(*type, options, ev, &message)) {
    case Decoded::kOk:
      break;
    case Decoded::kUnverified:
      ++out->unverified;
      break;
    case Decoded::kUnauthenticated:
      ++out->unauthenticated;
      return;
    case Decoded::kFailed:
      t->decode_failed.Add(ev.channel + " (" + type->name + ", " + std::to_string(ev.data.size()) +
                           " bytes)");
      return;
  }
  ++out->pidlab_messages;
  assembler->Add(prefix, message);
}

// How far the file was read, and the note on its tail.
void RecordEnd(const EventReader& reader, LogContents* out) {
  out->events = reader.events();
  out->eventnum_gaps = reader.eventnum_gaps();
  out->bytes_read = reader.bytes_read();
  out->clean_end = reader.clean();
  if (!reader.has_tail()) return;
  std::ostringstream os;
  os << "the log ends with " << reader.tail_bytes() << " bytes that are not a complete event (from byte "
     << reader.tail_offset()
     << "): it was cut off mid-write or its tail is corrupt; everything before was read";
  out->notes.push_back(os.str());
}

// The counters and the grouped notes, in the order of LogContents.
void RecordTallies(const Tallies& t, LogContents* out) {
  out->foreign = t.foreign.count;
  out->unknown_type = t.unknown_type.count;
  out->decode_failures = t.decode_failed.count;
  out->other_prefix = t.other_prefix.count;
  out->orphan_messages = t.orphans.count;
  auto note = [out](const Tally& tally, const std::string& what) {
    if (tally.count) out->notes.push_back(std::to_string(tally.count) + " " + what + ": " + tally.Examples());
  };
  note(t.foreign, "events on non-pidlab channels ignored");
  note(t.unknown_type,
       "events on pidlab-named channels with an unknown fingerprint (a changed or foreign type) ignored");
  note(t.decode_failed, "pidlab events that do not decode (corrupt payload) ignored");
  note(t.other_prefix, "pidlab events of other channel prefixes skipped");
  note(t.orphans, "episodes whose configuration is not in the log (listed, not evaluated)");
  if (out->unauthenticated)
    out->notes.push_back(
        std::to_string(out->unauthenticated) +
        " pidlab events without a valid tag for the key given (forged or unauthenticated) dropped");
  if (out->unverified)
    out->notes.push_back(std::to_string(out->unverified) +
                         " pidlab events carry an authentication tag that was not checked (give --auth-key)");
  note(t.unreadable, "unreadable stretches skipped, reading resumed at the next event marker");
  if (out->self_test) out->notes.push_back(std::to_string(out->self_test) + " LCM self-test events ignored");
}

}  // namespace

long StreamStats::MissingCount() const {
  long n = 0;
  for (const auto& [a, b] : missing) n += b - a + 1;
  return n;
}

bool Episode::Complete() const {
  return has_config && outputs.missing.empty() && commands.missing.empty() && disturbances.missing.empty();
}

std::string Episode::CompletenessNote() const {
  if (!has_config)
    return config_error.empty() ? "no episode configuration in the log"
                                : "invalid configuration: " + config_error;
  std::ostringstream os;
  auto stream = [&os](const char* what, const StreamStats& s) {
    if (s.missing.empty()) return;
    if (os.tellp() > 0) os << "; ";
    os << s.MissingCount() << " of " << s.expected << " " << what << " missing (steps " << Ranges(s.missing)
       << ")";
  };
  stream("plant outputs", outputs);
  stream("commands", commands);
  stream("disturbance samples", disturbances);
  return os.str();
}

// The event reader's events, through the decoder table, into the episode
// assembler.
Status ReadLog(const std::string& path, const ReadOptions& options, LogContents* out) {
  *out = LogContents();
  EventReader reader;
  if (Status st = reader.Open(path); !st.ok()) return st;
  out->opened = true;
  out->file_bytes = reader.file_bytes();
  Tallies tallies;
  reader.OnSkip([&tallies](const SkippedBytes& s) { tallies.unreadable.Add(Describe(s)); });
  const DecoderTable table;
  EpisodeAssembler assembler;
  for (LogEvent event; reader.Next(&event);) HandleEvent(table, options, event, &assembler, &tallies, out);
  RecordEnd(reader, out);
  for (const lcmt_episode_config& config : options.supplied_configs)
    assembler.Supply(options.channel_prefix, config);
  AssembledEpisodes assembled = assembler.Finish();
  for (const std::string& orphan : assembled.orphans) tallies.orphans.Add(orphan);
  out->notes.insert(out->notes.end(), assembled.notes.begin(), assembled.notes.end());
  out->episodes = std::move(assembled.episodes);
  RecordTallies(tallies, out);
  if (out->events == 0) {
    return Status::InvalidInput("'" + path + "' holds no LCM event (" +
                                (out->file_bytes == 0
                                     ? std::string("an empty file")
                                     : std::to_string(out->file_bytes) + " bytes: not an LCM log?") +
                                ")");
  }
  return Status::Ok();
}

}  // namespace pidlab::replay
