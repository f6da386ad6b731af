#include "pidlab/tune/batch.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/tune/search_box.h"
#include "pidlab/tune/tune.h"

namespace pidlab::tune {

using evaluation::LoopKind;
using evaluation::LoopOptions;

bool BatchOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(steps_per_delay >= 1.0 && steps_per_delay <= 1000.0))
    os << "steps per delay " << steps_per_delay << " must be in [1, 1000]";
  else if (!(horizon_factor >= 1.0 && horizon_factor <= 1000.0))
    os << "horizon factor " << horizon_factor << " must be in [1, 1000]";
  else if (!(stability_margin >= 0.0 && stability_margin < 1.0))
    os << "stability margin " << stability_margin << " must be in [0, 1)";
  else if (!(filter_ratio > 0.0 && std::isfinite(filter_ratio)))
    os << "filter ratio " << filter_ratio << " must be positive and finite";
  else if (!(max_ms > 1.0 && std::isfinite(max_ms)))
    os << "max Ms " << max_ms << " must be finite and > 1";
  else if (!(ms_tolerance >= 0.0 && ms_tolerance < 0.1))
    os << "Ms tolerance " << ms_tolerance << " must be in [0, 0.1)";
  else if (search_evaluations < 2 || polish_evaluations < 1)
    os << "budgets " << search_evaluations << ", " << polish_evaluations << " must be >= 2 and >= 1";
  else if (jobs < 0 || jobs > 1024)
    os << "jobs " << jobs << " must be in [0, 1024]";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The loop both controllers are scored on: dt = L / steps_per_delay, the
// error sampled every dt, over horizon_factor (L + Ti).
LoopOptions BatchLoop(const BatchOptions& o, const ProcessModel& model, double ti_s) {
  LoopOptions loop;
  loop.loop = o.loop;
  const double dt = model.delay_s / o.steps_per_delay;
  const double steps = std::ceil(o.horizon_factor * (model.delay_s + ti_s) / dt);
  loop.dt_s = dt;
  loop.sample_time_s = dt;
  loop.horizon_s = steps * dt;
  loop.stability_margin = o.stability_margin;
  loop.derivative_filter_ratio = o.filter_ratio;
  return loop;
}

struct Score {
  double ms = kNaN, load_iae = kNaN;
  bool stable = false;
};

// The load IAE (ts x the sum of |y| at the samples, r = 0, a unit step at the
// plant input) and Ms by the full analysis of the loop scored.
Score ScoreGains(const Plant& plant, const PidGains& g, const LoopOptions& loop) {
  Score s;
  const evaluation::ObjectiveEvaluator evaluator(plant, loop, evaluation::ObjectiveKind::kLoadIae);
  const double sum = evaluator(g);
  if (!std::isfinite(sum)) return s;
  s.load_iae = loop.sample_time_s * sum;
  analysis::LoopAnalysis a;
  if (!analysis::AnalyzeLoop(plant, evaluation::LoopGains(g, loop), loop, analysis::LoopAnalysisOptions{}, &a)
           .ok() ||
      !a.stable)
    return s;
  s.ms = a.ms;
  s.stable = std::isfinite(a.ms);
  return s;
}

void AmigoPart(const TuningRuleResult& rule, const Plant& plant, const LoopOptions& loop,
               const BatchOptions& o, BatchResult* r) {
  r->amigo_gains = evaluation::LoopGains(rule.gains, loop);
  const Score s = ScoreGains(plant, rule.gains, loop);
  r->amigo_ms = s.ms;
  r->amigo_load_iae = s.load_iae;
  r->amigo_feasible = s.stable && s.ms <= o.max_ms + o.ms_tolerance;
}

// Tune on the load IAE under Ms <= max_ms, by `method` (multi-start over the
// box, or Nelder-Mead from `start`).
TuneSummary Search(const Plant& plant, const LoopOptions& loop, const BatchOptions& o, double upper,
                   TuneMethod method, const PidGains& start) {
  TuneOptions t;
  t.method = method;
  t.objective = evaluation::ObjectiveKind::kLoadIae;
  t.loop = loop;
  t.upper = upper;
  t.bounds.max_ms = o.max_ms;
  t.refine = false;
  t.seed = o.seed;
  if (method == TuneMethod::kMultiStart) {
    t.max_evaluations = o.search_evaluations;
    t.design_points = std::max(1, o.search_evaluations / 4);
    t.starts = 8;
  } else {
    t.max_evaluations = o.polish_evaluations;
    t.starts = 1;
    t.start = {std::min(start.kp, upper), std::min(start.ki, upper), std::min(start.kd, upper)};
  }
  TuneSummary s;
  std::string error;
  if (const Status st = Tune(plant, t, &s); !st.ok()) s.message = st.message();
  return s;
}

// AMIGO's gains times the largest c in (0, 1] (bisection, 2^-14) whose loop
// has Ms <= max_ms by the full analysis: a feasible start for the search
// when AMIGO's own loop is not. Empty gains when no c is found.
PidGains DetunedAmigo(const Plant& plant, const PidGains& amigo, const LoopOptions& loop,
                      const BatchOptions& o, bool amigo_feasible) {
  if (amigo_feasible) return amigo;
  const auto scaled = [&amigo](double c) { return PidGains{c * amigo.kp, c * amigo.ki, c * amigo.kd, 0.0}; };
  const auto meets = [&](double c) {
    analysis::LoopAnalysis a;
    return analysis::AnalyzeLoop(plant, evaluation::LoopGains(scaled(c), loop), loop,
                                 analysis::LoopAnalysisOptions{}, &a)
               .ok() &&
           a.stable && a.ms <= o.max_ms;
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 14; ++i) {
    const double mid = 0.5 * (lo + hi);
    (meets(mid) ? lo : hi) = mid;
  }
  return lo > 0.0 ? scaled(lo) : PidGains{};
}

// The best of the candidates that meet Ms <= max_ms by the full analysis.
void PidlabPart(const BatchPlant& bp, const TuningRuleResult& rule, const LoopOptions& loop,
                const BatchOptions& o, BatchResult* r) {
  struct Candidate {
    std::string source;
    PidGains gains;
  };
  std::vector<Candidate> candidates;
  const PidGains start = DetunedAmigo(bp.plant, rule.gains, loop, o, r->amigo_feasible);
  const TuneSummary multi = Search(bp.plant, loop, o, r->box_upper, TuneMethod::kMultiStart, start);
  if (multi.stable) candidates.push_back({"multi-start", multi.gains});
  const TuneSummary polish = Search(bp.plant, loop, o, r->box_upper, TuneMethod::kNelderMead, start);
  if (polish.stable) candidates.push_back({"nelder-mead from amigo", polish.gains});
  if (r->amigo_feasible) candidates.push_back({"amigo", rule.gains});
  if (!r->amigo_feasible && start.kp > 0.0) candidates.push_back({"amigo detuned", start});
  r->load_iae = r->ms = kNaN;
  for (const Candidate& c : candidates) {
    const Score s = ScoreGains(bp.plant, c.gains, loop);
    if (!s.stable || s.ms > o.max_ms + o.ms_tolerance) continue;
    if (r->feasible && !(s.load_iae < r->load_iae)) continue;
    r->feasible = true;
    r->source = c.source;
    r->gains = evaluation::LoopGains(c.gains, loop);
    r->ms = s.ms;
    r->load_iae = s.load_iae;
  }
  if (!r->feasible) {
    r->message = "no gains found with Ms <= " + std::to_string(o.max_ms) + ": " + multi.message;
    return;
  }
  r->at_bounds = GainsAtBounds(r->gains, 0.0, r->box_upper);
  r->ratio = std::isfinite(r->amigo_load_iae) ? r->load_iae / r->amigo_load_iae : kNaN;
}

}  // namespace

Status RunBatchPlant(const BatchPlant& bp, const BatchOptions& o, BatchResult* r) {
  std::string error;
  if (!o.IsValid(&error)) return Status::InvalidInput(error);
  const auto start = std::chrono::steady_clock::now();
  *r = BatchResult();
  r->plant = bp;
  r->amigo_ms = r->amigo_load_iae = r->ms = r->load_iae = r->ratio = kNaN;
  TuningRuleResult rule;
  Status status = ReduceFactored(bp.factors, TuningRule::kAmigo, RuleForm::kPid, &r->model);
  if (status.ok()) status = AmigoTune(r->model, RuleForm::kPid, &rule);
  if (!status.ok()) {
    r->message = status.message();
    return Status::Ok();
  }
  r->amigo_k = rule.kc;
  r->amigo_ti_s = rule.ti_s;
  r->amigo_td_s = rule.td_s;
  const bool ipdt = r->model.kind == ProcessModelKind::kIntegrating;
  r->tau = ipdt ? 0.0 : r->model.delay_s / (r->model.delay_s + r->model.time_constants[0]);
  const LoopOptions loop = BatchLoop(o, r->model, rule.ti_s);
  r->dt_s = loop.dt_s;
  r->horizon_s = loop.horizon_s;
  r->box_upper = kPlantBoxFactor * std::max({rule.gains.kp, rule.gains.ki, rule.gains.kd});
  if (!loop.IsValid(&error)) {
    r->message = error;
    return Status::Ok();
  }
  if (const Status st = evaluation::DelayIsValid(bp.plant, loop, "delay"); !st.ok()) {
    r->message = st.message();
    return Status::Ok();
  }
  if (loop.loop == evaluation::LoopKind::kContinuous && bp.plant.delay_s > 0.0) {
    // The continuous loop takes a dead time (the method of steps), but at a
    // step of 0.02 / (fastest rate) over the batch's horizon of 20 (L + Ti)
    // one evaluation of a lag-dominated plant takes tens of milliseconds:
    // thousands of them a plant are too many for a batch.
    r->message = "dead time " + std::to_string(bp.plant.delay_s) +
                 " s: the batch scores plants with dead time on --loop sampled (on the continuous loop the "
                 "method of steps is too slow for its searches)";
    return Status::Ok();
  }
  AmigoPart(rule, bp.plant, loop, o, r);
  PidlabPart(bp, rule, loop, o, r);
  r->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

Status RunBatch(const std::vector<BatchPlant>& plants, const BatchOptions& options,
                std::vector<BatchResult>* results, const std::function<void(int done, int total)>& progress) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  results->assign(plants.size(), BatchResult());
  const int total = static_cast<int>(plants.size());
  int jobs = options.jobs > 0 ? options.jobs : static_cast<int>(std::thread::hardware_concurrency());
  jobs = std::max(1, std::min(jobs, total));
  std::atomic<int> next{0};
  int done = 0;
  std::mutex mutex;
  const auto work = [&] {
    for (int i = next++; i < total; i = next++) {
      RunBatchPlant(plants[static_cast<std::size_t>(i)], options, &(*results)[static_cast<std::size_t>(i)]);
      const std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (progress) progress(done, total);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  return Status::Ok();
}

BatchTally TallyBatch(const std::vector<BatchResult>& results) {
  BatchTally t;
  double best = std::numeric_limits<double>::infinity(), worst = 0.0, max_ms = 0.0;
  for (const BatchResult& r : results) {
    ++t.plants;
    t.amigo_feasible += r.amigo_feasible ? 1 : 0;
    t.pidlab_feasible += r.feasible ? 1 : 0;
    if (r.feasible) max_ms = std::max(max_ms, r.ms);
    if (!r.amigo_feasible || !r.feasible) continue;
    if (r.ratio < 1.0 - 1e-9)
      ++t.wins;
    else if (r.ratio > 1.0 + 1e-9)
      ++t.losses;
    else
      ++t.ties;
    worst = std::max(worst, r.ratio);
    best = std::min(best, r.ratio);
  }
  if (std::isfinite(best)) {
    t.best_ratio = best;
    t.worst_ratio = worst;
  }
  if (t.pidlab_feasible > 0) t.max_ms = max_ms;
  return t;
}

}  // namespace pidlab::tune
