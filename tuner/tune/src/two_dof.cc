#include "pidlab/tune/two_dof.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/optim/nelder_mead.h"

namespace pidlab::tune {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

evaluation::LoopOptions Weighted(evaluation::LoopOptions loop, double b, double c) {
  loop.pid.setpoint_weight_b = b;
  loop.pid.setpoint_weight_c = c;
  return loop;
}

// The setpoint step's IAE with weights b, c: the loop without its
// disturbance; +inf where it cannot be evaluated.
double SetpointIae(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& loop, double b,
                   double c) {
  evaluation::LoopOptions o = Weighted(loop, b, c);
  o.disturbance = DisturbanceOptions{};
  evaluation::EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  what.compute_load_iae = false;
  evaluation::Evaluation ev;
  if (!evaluation::Evaluate(plant, gains, o, what, &ev).ok() || !ev.stability.stable) return kInf;
  return std::isfinite(ev.iae) ? ev.iae : kInf;
}

// The loop's responses at the weights b, c. `feedback`, when given, is the
// same loop's response at other weights: its load IAE and Ms are taken
// as they are, since the weights move no pole and not the response to a load
// (bit for bit: two_dof_test.cc, "...DoNotDependOnTheWeights...").
bool Respond(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& loop, double b,
             double c, TwoDofResponse* r, std::string* error, const TwoDofResponse* feedback = nullptr) {
  evaluation::LoopOptions o = Weighted(loop, b, c);
  o.disturbance = DisturbanceOptions{};
  evaluation::EvaluateOptions what;
  what.compute_load_iae = feedback == nullptr;
  evaluation::Evaluation ev;
  if (const Status st = evaluation::Evaluate(plant, gains, o, what, &ev); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  r->b = b;
  r->c = c;
  r->setpoint_iae = ev.iae;
  r->overshoot_pct = ev.step.overshoot_pct;
  r->rise_time_s = ev.step.rise_time_s;
  r->settling_time_s = ev.step.settling_time_s;
  if (feedback) {
    r->load_iae = feedback->load_iae;
    r->ms = feedback->ms;
    return true;
  }
  analysis::LoopAnalysis a;
  if (const Status st = analysis::AnalyzeLoop(plant, gains, o, analysis::LoopAnalysisOptions{}, &a);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  r->load_iae = ev.load_iae;
  r->ms = a.ms;
  return true;
}

}  // namespace

namespace {

// TuneSetpointWeights() with the refusal's message in *error.
bool TuneSetpointWeightsOrExplain(const Plant& plant, const PidGains& gains,
                                  const evaluation::LoopOptions& loop, TwoDofSummary* summary,
                                  std::string* error) {
  *summary = TwoDofSummary();
  const double b0 = loop.pid.setpoint_weight_b, c0 = loop.pid.setpoint_weight_c;
  if (!Respond(plant, gains, loop, b0, c0, &summary->before, error)) return false;
  const auto f = [&](const Eigen::VectorXd& x) { return SetpointIae(plant, gains, loop, x(0), x(1)); };
  // A grid first (the IAE of a weighted loop can have several minima), then
  // Nelder-Mead in the box from its best point.
  Eigen::VectorXd best = Eigen::Vector2d(b0, c0);
  double best_f = f(best);
  int evaluations = 1;
  for (int i = 0; i < kTwoDofGridPoints; ++i) {
    for (int j = 0; j < kTwoDofGridPoints; ++j) {
      const Eigen::Vector2d x(i / (kTwoDofGridPoints - 1.0), j / (kTwoDofGridPoints - 1.0));
      const double v = f(x);
      ++evaluations;
      if (v < best_f) best_f = v, best = x;
    }
  }
  if (!std::isfinite(best_f)) {
    summary->evaluations = evaluations;
    summary->message = "the setpoint response cannot be evaluated for any weights";
    return true;
  }
  optim::NelderMeadOptions nm;
  nm.x0 = best;
  nm.max_evaluations = kTwoDofMaxEvaluations;
  nm.x_tolerance = 1e-7;
  optim::OptimizerSummary opt;
  optim::NelderMead(f, optim::Bounds{Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 1.0)}, nm, &opt);
  summary->evaluations = evaluations + opt.evaluations;
  summary->termination = opt.termination;
  summary->message = opt.message;
  if (opt.IsUsable() && opt.f < best_f) best = opt.x;
  summary->b = best(0);
  summary->c = best(1);
  if (!Respond(plant, gains, loop, summary->b, summary->c, &summary->after, error, &summary->before))
    return false;
  summary->ran = true;
  return true;
}

}  // namespace

Status TuneSetpointWeights(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& loop,
                           TwoDofSummary* summary) {
  std::string why;
  if (!TuneSetpointWeightsOrExplain(plant, gains, loop, summary, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

namespace {

// SetpointWeightForOvershoot() with the refusal's message in *error.
bool SetpointWeightForOvershootOrExplain(const Plant& plant, const PidGains& gains,
                                         const evaluation::LoopOptions& loop, double c,
                                         double max_overshoot_pct, TwoDofSummary* summary,
                                         std::string* error) {
  *summary = TwoDofSummary();
  if (!Respond(plant, gains, loop, 1.0, c, &summary->before, error)) return false;
  summary->evaluations = 1;
  double b = 1.0;
  if (!(summary->before.overshoot_pct <= max_overshoot_pct)) {
    // The overshoot alone (no analysis: the weights move no pole).
    const auto overshoot = [&](double weight) {
      evaluation::LoopOptions o = Weighted(loop, weight, c);
      o.disturbance = DisturbanceOptions{};
      evaluation::EvaluateOptions what;
      what.compute_iae_continuous = false;
      what.compute_load_iae = false;
      evaluation::Evaluation ev;
      ++summary->evaluations;
      if (!evaluation::Evaluate(plant, gains, o, what, &ev).ok() || !ev.stability.stable) return kInf;
      return ev.step.overshoot_pct;
    };
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 8; ++i) {
      const double mid = 0.5 * (lo + hi);
      (overshoot(mid) <= max_overshoot_pct ? lo : hi) = mid;
    }
    b = lo;
  }
  if (!Respond(plant, gains, loop, b, c, &summary->after, error, &summary->before)) return false;
  summary->b = b;
  summary->c = c;
  summary->termination = optim::TerminationType::kConverged;
  std::ostringstream os;
  os << "b for a setpoint overshoot <= " << max_overshoot_pct << " % (bisection), c = " << c;
  summary->message = os.str();
  summary->ran = true;
  return true;
}

}  // namespace

Status SetpointWeightForOvershoot(const Plant& plant, const PidGains& gains,
                                  const evaluation::LoopOptions& loop, double c, double max_overshoot_pct,
                                  TwoDofSummary* summary) {
  std::string why;
  if (!SetpointWeightForOvershootOrExplain(plant, gains, loop, c, max_overshoot_pct, summary, &why))
    return Status::InvalidInput(why);
  return Status::Ok();
}

evaluation::LoopOptions WithSetpointWeights(evaluation::LoopOptions loop, const TwoDofSummary& summary) {
  if (!summary.ran) return loop;
  loop = Weighted(loop, summary.b, summary.c);
  loop.pid.setpoint_filter_s = summary.setpoint_filter_s;
  return loop;
}

}  // namespace pidlab::tune
