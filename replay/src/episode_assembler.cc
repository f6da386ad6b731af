#include "pidlab/replay/episode_assembler.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

#include "pidlab/transport/episode_spec.h"

namespace pidlab::replay {
namespace {

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Per-step values of one stream, as first received.
struct StepRecord {
  double a = 0, b = 0, c = 0;
  int status = -1;
};

// The largest step any episode can have.
constexpr long kLastPossibleStep = static_cast<long>(transport::kMaxEpisodeSteps);

bool Possible(long k) { return k >= 0 && k <= kLastPossibleStep; }

// One stream of an episode: each step as first received, plus what happened.
// Steps no episode can have (negative, beyond kMaxEpisodeSteps, or past the
// largest long) are counted, never stored.
struct Stream {
  std::map<long, StepRecord> steps;
  long duplicates = 0, conflicts = 0, out_of_order = 0, max_seen = -1;
  long impossible = 0;

  void Add(long k, const StepRecord& r) {
    if (!Possible(k)) {
      ++impossible;
      return;
    }
    auto it = steps.find(k);
    if (it == steps.end()) {
      if (k < max_seen) ++out_of_order;
      max_seen = std::max(max_seen, k);
      steps.emplace(k, r);
    } else if (SameBits(it->second.a, r.a) && SameBits(it->second.b, r.b) && SameBits(it->second.c, r.c) &&
               it->second.status == r.status) {
      ++duplicates;
    } else {
      ++conflicts;
    }
  }
  bool empty() const { return steps.empty() && impossible == 0; }
};

// Step first + i of a block or chunk; false if it is past the largest long.
bool StepAt(int64_t first, long i, long* k) {
  static_assert(sizeof(long) >= sizeof(int64_t), "steps are int64 in the messages");
  if (first > std::numeric_limits<long>::max() - i) return false;
  *k = static_cast<long>(first) + i;
  return true;
}

// Hands every step present in 0..last to put(k, record, from_chunk).
using PutStep = std::function<void(long, const StepRecord&, bool)>;

// Statistics of one stream over steps 0..last: its own steps first, then the
// trajectory chunks fill the steps it lacks where their `field` is finite.
// Walks both maps in step order, so no per-step memory is needed.
StreamStats Summarize(const Stream& s, const std::map<long, StepRecord>& chunks, double StepRecord::*field,
                      long last, const PutStep& put) {
  StreamStats st;
  st.expected = last + 1;
  st.duplicates = s.duplicates;
  st.conflicts = s.conflicts;
  st.out_of_order = s.out_of_order;
  st.beyond_end = s.impossible;
  for (const auto& step : s.steps)
    if (step.first > last) ++st.beyond_end;
  auto own = s.steps.begin();
  auto chunk = chunks.lower_bound(0);
  long next = 0;  // first step not yet accounted for
  for (;;) {
    while (chunk != chunks.end() && chunk->first <= last &&
           (!std::isfinite(chunk->second.*field) || s.steps.count(chunk->first)))
      ++chunk;
    const bool own_ok = own != s.steps.end() && own->first <= last;
    const bool chunk_ok = chunk != chunks.end() && chunk->first <= last;
    if (!own_ok && !chunk_ok) break;
    const bool from_chunk = !own_ok || (chunk_ok && chunk->first < own->first);
    const auto& [k, r] = from_chunk ? *chunk++ : *own++;
    ++(from_chunk ? st.filled_from_chunks : st.received);
    if (put) put(k, r, from_chunk);
    if (k > next) st.missing.push_back({next, k - 1});
    next = k + 1;
  }
  if (next <= last) st.missing.push_back({next, last});
  return st;
}

void AllocateSteps(Episode* e) {
  const auto size = static_cast<std::size_t>(e->total_steps + 1);
  e->y.assign(size, std::nan(""));
  e->u.assign(size, std::nan(""));
  e->n.assign(size, std::nan(""));
  e->u_input_y.assign(size, std::nan(""));
  e->status.assign(size, -1);
  e->has_y.assign(size, 0);
  e->has_u.assign(size, 0);
  e->has_n.assign(size, 0);
}

// Encodings of two configurations, timestamps aside, are identical.
bool SameConfig(pidlab::lcmt_episode_config a, pidlab::lcmt_episode_config b) {
  a.utime = b.utime = 0;
  if (a.getEncodedSize() != b.getEncodedSize()) return false;
  std::vector<uint8_t> x(static_cast<std::size_t>(a.getEncodedSize())), y(x.size());
  a.encode(x.data(), 0, static_cast<int>(x.size()));
  b.encode(y.data(), 0, static_cast<int>(y.size()));
  return x == y;
}

}  // namespace

struct EpisodeAssembler::Building {
  Episode episode;
  bool config_conflict = false;
  pidlab::lcmt_episode_config config;
  Stream outputs, commands, disturbances;
  std::map<long, StepRecord> chunks;  // y, u, n from the plant's trajectory chunks

  bool HasData() const { return !outputs.empty() || !commands.empty() || !disturbances.empty(); }
  long TotalSteps() const;
  void Assemble();
};

// The configuration's total_steps; for an orphan, the highest step of its
// data (within what an episode can have).
long EpisodeAssembler::Building::TotalSteps() const {
  if (episode.has_config) return std::clamp<long>(episode.spec.total_steps, 0, kLastPossibleStep);
  long total = 0;
  for (const Stream* s : {&outputs, &commands, &disturbances})
    if (!s->steps.empty()) total = std::max(total, s->steps.rbegin()->first);
  return total;
}

void EpisodeAssembler::Building::Assemble() {
  Episode& e = episode;
  const long total = e.total_steps = TotalSteps();
  PutStep put_y, put_u, put_n;
  if (e.has_config) {
    AllocateSteps(&e);
    put_y = [&e](long k, const StepRecord& r, bool) { e.y[k] = r.a, e.has_y[k] = 1; };
    put_u = [&e](long k, const StepRecord& r, bool chunk) {
      if (chunk)
        e.u[k] = r.b;
      else
        e.u[k] = r.a, e.u_input_y[k] = r.b, e.status[k] = r.status;
      e.has_u[k] = 1;
    };
    put_n = [&e](long k, const StepRecord& r, bool chunk) { e.n[k] = chunk ? r.c : r.a, e.has_n[k] = 1; };
  }
  e.outputs = Summarize(outputs, chunks, &StepRecord::a, total, put_y);
  e.commands = Summarize(commands, chunks, &StepRecord::b, total - 1, put_u);
  e.disturbances = Summarize(disturbances, chunks, &StepRecord::c, total - 1, put_n);
}

EpisodeAssembler::EpisodeAssembler() = default;
EpisodeAssembler::~EpisodeAssembler() = default;

EpisodeAssembler::Building& EpisodeAssembler::EpisodeOf(const std::string& prefix, int64_t episode_id) {
  const auto [it, added] = index_.emplace(std::make_pair(prefix, episode_id), building_.size());
  if (added) {
    building_.push_back(std::make_unique<Building>());
    building_.back()->episode.prefix = prefix;
    building_.back()->episode.episode_id = episode_id;
  }
  return *building_[it->second];
}

void EpisodeAssembler::Add(const std::string& prefix, const PidlabMessage& message) {
  std::visit([this, &prefix](const auto& m) { On(prefix, m); }, message);
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_episode_config& m) {
  Building& b = EpisodeOf(prefix, m.episode_id);
  if (b.episode.has_config || !b.episode.config_error.empty()) {
    if (!SameConfig(m, b.config)) b.config_conflict = true;
    return;
  }
  b.config = m;
  b.episode.config = m;
  if (const Status st = transport::ParseEpisodeConfig(m, &b.episode.spec); st.ok())
    b.episode.has_config = true;
  else
    b.episode.config_error = st.message();
}

void EpisodeAssembler::Supply(const std::string& prefix, const pidlab::lcmt_episode_config& config) {
  Building& b = EpisodeOf(prefix, config.episode_id);
  if (b.episode.has_config || !b.episode.config_error.empty()) return;
  On(prefix, config);
  b.episode.config_supplied = true;
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_plant_output& m) {
  EpisodeOf(prefix, m.episode_id).outputs.Add(m.step, {m.y, m.t_s, 0, -1});
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_control_command& m) {
  EpisodeOf(prefix, m.episode_id).commands.Add(m.step, {m.u, m.y, m.r, m.status});
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_disturbance_sample& m) {
  EpisodeOf(prefix, m.episode_id).disturbances.Add(m.step, {m.n, m.t_s, 0, -1});
}

// n_k for k in [step, step + count): each sample counts as the step's
// disturbance sample (a resent block gives duplicates, as resent samples did).
void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_disturbance_block& m) {
  Stream& d = EpisodeOf(prefix, m.episode_id).disturbances;
  const long count = std::min<long>(m.count, static_cast<long>(m.n.size()));
  for (long i = 0, k = 0; i < count; ++i) {
    if (StepAt(m.step, i, &k))
      d.Add(k, {m.n[static_cast<std::size_t>(i)], static_cast<double>(k) * m.dt_s, 0, -1});
    else
      ++d.impossible;
  }
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_episode_summary& m) {
  Episode& e = EpisodeOf(prefix, m.episode_id).episode;
  e.has_summary = true;
  e.summary_status = m.status;
  e.summary_step = static_cast<long>(m.step);
  e.summary_message = m.message;
  e.realtime = transport::RealtimeFromSummary(m);
}

void EpisodeAssembler::On(const std::string& prefix, const pidlab::lcmt_trajectory_chunk& m) {
  Building& b = EpisodeOf(prefix, m.episode_id);
  const long count =
      std::min<long>(m.count, static_cast<long>(std::min({m.y.size(), m.u.size(), m.n.size()})));
  for (long i = 0, k = 0; i < count && StepAt(m.step, i, &k); ++i) {
    const auto at = static_cast<std::size_t>(i);
    if (Possible(k)) b.chunks.emplace(k, StepRecord{m.y[at], m.u[at], m.n[at], -1});
  }
}

AssembledEpisodes EpisodeAssembler::Finish() {
  AssembledEpisodes out;
  for (const std::unique_ptr<Building>& b : building_) {
    Episode& e = b->episode;
    if (!e.has_config && e.config_error.empty() && !b->HasData()) continue;  // acks, summaries, chunks only
    if (!e.has_config) out.orphans.push_back(e.prefix + " episode " + std::to_string(e.episode_id));
    b->Assemble();
    if (b->config_conflict)
      out.notes.push_back(e.prefix + " episode " + std::to_string(e.episode_id) +
                          ": the configuration was logged more than once with different content; the first "
                          "is used");
    out.episodes.push_back(std::move(e));
  }
  building_.clear();
  index_.clear();
  return out;
}

}  // namespace pidlab::replay
