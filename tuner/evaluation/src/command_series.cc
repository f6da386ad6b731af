// The command and the load response at the sample times (command_series.h):
// the continuous loop's from its state, the delayed loop's by its samplers,
// the sampled loop's as recorded.

#include "pidlab/evaluation/command_series.h"

#include <algorithm>

#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/evaluation/delayed_loop.h"
#include "pidlab/plant_sim/matrix_exp.h"

namespace pidlab::evaluation {
namespace {

// y and u of a continuous loop (no breakpoints: no disturbance, or the load
// step from t = 0) at t = 0, ts, ...: the loop's state propagated by
// e^{M ts} as SampleContinuousLoop does, and u from the plant's row of
// w' = M w: B u = x' - A x - B n.
void ContinuousResponseAndCommand(const StateSpace& ss, const ContinuousClosedLoop<double>& loop, double ts,
                                  int samples, std::vector<double>* y, std::vector<double>* u) {
  const Eigen::MatrixXd phi = MatrixExp<double>(Eigen::MatrixXd(loop.m * ts));
  const int n = loop.plant_order;
  const double bb = ss.b.squaredNorm();
  Eigen::VectorXd w = loop.w0, next(w.size());
  y->clear();
  u->clear();
  for (int k = 0; k < samples; ++k) {
    if (k > 0) {
      next.noalias() = phi * w;
      w.swap(next);
    }
    const Eigen::VectorXd x = w.head(n);
    const Eigen::VectorXd dx = (loop.m * w).head(n);
    const double disturbance = loop.exo_size == 1 ? w(loop.exo_index()) : 0.0;
    y->push_back(loop.Output(w));
    u->push_back(ss.b.dot(dx - ss.a * x) / bb - disturbance);
  }
}

// u of a delayed loop at the sample times: the loop's q = u + n sampled by
// the evaluation's samplers (the output row kq over the whole state), less
// the disturbance n(t) that enters q.
bool DelayedCommand(const DelayedClosedLoop& loop, const Disturbance& disturbance, double ts, int samples,
                    std::vector<double>* u) {
  DelayedClosedLoop q = loop;
  q.c = loop.kq;
  q.plant_order = static_cast<int>(loop.kq.size());
  DelayedTrace trace;
  if (!SampleDelayedLoop(q, disturbance, ts, samples, u, &trace).ok()) return false;
  if (loop.exo_size > 0)
    for (int k = 0; k < samples; ++k) (*u)[k] -= disturbance.Value(k * ts);
  return true;
}

// y and u of the continuous loop with dead time (the setpoint response when
// `reference` is 1, the load response at 0 with the load step).
bool DelayedResponseAndCommand(const Plant& plant, const PidGains& gains, const Disturbance& disturbance,
                               double reference, const SetpointWeights& weights, const LoopOptions& options,
                               std::vector<double>* y, std::vector<double>* u) {
  DelayedClosedLoop loop;
  DelayedTrace trace;
  const int samples = options.NumSamples();
  const bool ok =
      BuildDelayedClosedLoop(plant.tf, Realize(plant.tf), gains, disturbance, plant.delay_s, reference, &loop,
                             weights)
          .ok() &&
      (!y || SampleDelayedLoop(loop, disturbance, options.sample_time_s, samples, y, &trace).ok()) &&
      DelayedCommand(loop, disturbance, options.sample_time_s, samples, u);
  if (!ok) {
    if (y) y->clear();
    u->clear();
  }
  return ok;
}

}  // namespace

void CommandAndLoadSeries(const Plant& plant, const PidGains& typed_gains, const LoopOptions& options,
                          const Evaluation& ev, CommandSeries* out) {
  *out = CommandSeries{};
  const PidGains gains = LoopGains(typed_gains, options);
  std::vector<double>&u = out->u, &load_y = out->load_y, &load_u = out->load_u;
  std::vector<std::string>* notes = &out->notes;
  const Disturbance load_step(UnitLoadStep());
  if (options.loop == LoopKind::kSampled) {
    const int every = options.StepsPerSample();
    for (std::size_t m = 0; m < ev.t.size() && !ev.trajectory.empty(); ++m)
      u.push_back(ev.trajectory[std::min(m * every, ev.trajectory.size() - 1)].u);
    if (plant.nonlinear) {
      notes->push_back("no load response for the nonlinear motor");
    } else {
      std::vector<SampledStep> steps;
      RunSampledLoop<double>(SampledPlant(plant, options.dt_s), gains, options.Pid(), load_step,
                             options.TotalSteps(), every, &load_y, &steps, 0.0);
      for (std::size_t m = 0; m < load_y.size(); ++m)
        load_u.push_back(steps[std::min(m * every, steps.size() - 1)].u);
    }
  } else if (plant.delay_s > 0.0) {
    // The evaluation library's delayed loop, as LoadIntegralAbsError and
    // the step response sample it; u by the same samplers.
    const Disturbance none{DisturbanceOptions{}};
    const SetpointWeights weights = SetpointWeightsOf(options.pid);
    DelayedResponseAndCommand(plant, gains, none, options.reference, weights, options, nullptr, &u);
    DelayedResponseAndCommand(plant, gains, load_step, 0.0, {}, options, &load_y, &load_u);
    if (gains.kd > 0.0 && !(gains.tf > 0.0) && weights.c != 0.0 && !(weights.filter_s > 0.0))
      notes->push_back("u leaves out the ideal derivative's impulse kd c r delta(t)");
    if (options.disturbance.kind != DisturbanceKind::kNone)
      notes->push_back("u is the command of the undisturbed step response");
  } else {
    const StateSpace ss = Realize(plant.tf);
    ContinuousClosedLoop<double> loop, load;
    std::vector<double> y_clean;
    const Disturbance none{DisturbanceOptions{}};
    if (BuildContinuousClosedLoop<double>(ss, gains, none, &loop, options.reference,
                                          SetpointWeightsOf(options.pid))
            .ok())
      ContinuousResponseAndCommand(ss, loop, options.sample_time_s, options.NumSamples(), &y_clean, &u);
    if (BuildContinuousClosedLoop<double>(ss, gains, load_step, &load, 0.0).ok())
      ContinuousResponseAndCommand(ss, load, options.sample_time_s, options.NumSamples(), &load_y, &load_u);
    if (options.disturbance.kind != DisturbanceKind::kNone)
      notes->push_back("u is the command of the undisturbed step response");
  }
}

}  // namespace pidlab::evaluation
