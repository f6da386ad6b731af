// The stepper motor on the sampled loop (the LCM trio's loop) in the paper
// report: computed and rendered.

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>

#include "format.h"
#include "report_internal.h"

using pidlab::evaluation::LoopOptions;

namespace pidlab::report {
namespace {

std::string MetricsCells(const Metrics& m) {
  if (!m.stable) return "unstable | | | ";
  return Num(m.rise_time_s, 5) + " | " + Num(m.overshoot_pct, 5) + " | " + Num(m.settling_time_s, 5) + " | " +
         Num(m.iae, 5);
}

void RenderSampledRow(std::ostream& os, const std::string& loop, const Metrics& m) {
  os << "| " << loop << " | " << (m.stable ? "yes" : "no") << " | " << MetricsCells(m) << " |\n";
}

// The table of the sampled section: continuous, sampled in process, and the
// trio's episode beside the in-process loop on its horizon.
void RenderSampledTable(std::ostream& os, const SampledSection& s) {
  os << "| loop | stable | rise [s] | overshoot [%] | settling [s] | IAE of y1 "
        "|\n|---|---|---:|---:|---:|---:|\n";
  RenderSampledRow(os, "continuous (exact)", s.continuous);
  RenderSampledRow(os, "sampled, in-process, dt = " + Num(s.dt_s, 5) + " s", s.sampled_in_process);
  RenderSampledRow(os, "sampled, in-process, dt = " + Num(s.fine_dt_s, 5) + " s", s.sampled_fine);
  if (s.trio_ran) {
    const std::string at = "dt = " + Num(s.dt_s, 5) + " s, horizon " + Num(s.trio_horizon_s, 5) + " s";
    RenderSampledRow(os, "sampled, in-process, " + at, s.sampled_trio_horizon);
    RenderSampledRow(os, "sampled, LCM trio, " + at, s.trio);
  }
  os << "\n";
}

// How the trio ran (or why not), and whether it matched the in-process loop.
void RenderTrioNote(std::ostream& os, const SampledSection& s) {
  os << (s.trio_ran ? "Trio run: " : "**The LCM trio run was not available**: ") << s.trio_note << ".";
  if (s.trio_ran) {
    const Metrics& a = s.trio;
    const Metrics& b = s.sampled_trio_horizon;
    const bool identical = a.stable == b.stable && a.iae == b.iae && a.rise_time_s == b.rise_time_s &&
                           a.overshoot_pct == b.overshoot_pct && a.settling_time_s == b.settling_time_s;
    if (s.trio_horizon_s < s.horizon_s) {
      os << " The episode covers " << Num(s.trio_horizon_s, 5) << " s instead of the paper's "
         << Num(s.horizon_s, 5) << " s; the slow tail after it adds "
         << Num(std::abs(s.sampled_in_process.iae - s.sampled_trio_horizon.iae), 3) << " to the IAE.";
    } else {
      os << " The episode covers the paper's full " << Num(s.trio_horizon_s, 5) << " s horizon.";
    }
    os << (identical
               ? std::string(" Its IAE and step metrics equal the in-process sampled loop's on the same "
                             "horizon bit for bit.")
               : " **Its results differ from the in-process sampled loop's** (IAE " + Num(a.iae, 17) +
                     " vs " + Num(b.iae, 17) + ").");
  }
  os << "\n\n";
}

// Why the sampled loop differs from the continuous one at dt, and converges
// at the finer dt.
void RenderSampledDiscussion(std::ostream& os, const SampledSection& s) {
  auto rel = [](double a, double b) { return 100.0 * std::abs(a - b) / std::abs(b); };
  os << "At dt = " << Num(s.dt_s, 5) << " s the sampled IAE is within "
     << Num(rel(s.sampled_in_process.iae, s.continuous.iae), 3)
     << " % of the continuous one and the overshoot is " << Num(s.sampled_in_process.overshoot_pct, 4)
     << " % against " << Num(s.continuous.overshoot_pct, 4) << " %: the plant's fastest pole is at "
     << Num(s.fastest_plant_pole_re, 4) << " rad/s (time constant " << Num(-1e3 / s.fastest_plant_pole_re, 3)
     << " ms) and the continuous rise time is " << Num(1e3 * s.continuous.rise_time_s, 3)
     << " ms, so one sample of the discrete PID (backward-Euler integral, backward-difference derivative) "
        "spans a large part of the transient. At dt = "
     << Num(s.fine_dt_s, 5) << " s the overshoot is " << Num(s.sampled_fine.overshoot_pct, 4)
     << " %: the sampled loop converges to the continuous one as dt shrinks. The 2 % settling time, set by "
        "the slow pole pair, is "
     << Num(s.sampled_in_process.settling_time_s, 4) << " s and " << Num(s.sampled_fine.settling_time_s, 4)
     << " s against " << Num(s.continuous.settling_time_s, 4) << " s continuous.\n\n";
}

}  // namespace

// The in-process part of the sampled section: the continuous loop, the
// sampled loop at dt and at the finer dt, the sampled loop over the trio's
// horizon, and the plant's fastest pole.
bool EvaluateSampledLoops(SampledSection* s, std::string* error) {
  const Plant stepper = BuiltinPlant("stepper_motor");
  if (const Status st = EvaluateMetrics(stepper, s->gains, 0.0, &s->continuous); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  LoopOptions sampled = PaperLoop(0.0);
  sampled.loop = evaluation::LoopKind::kSampled;
  sampled.dt_s = s->dt_s;
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  // The gains on `loop`, their metrics into *metrics; false with *error.
  const auto evaluate = [&](const LoopOptions& loop, Metrics* metrics) {
    evaluation::Evaluation ev;
    if (const Status st = evaluation::Evaluate(stepper, s->gains, loop, what, &ev); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    FillFromEvaluation(ev, metrics);
    return true;
  };
  if (!evaluate(sampled, &s->sampled_in_process)) return false;
  LoopOptions short_horizon = sampled;
  short_horizon.horizon_s = s->trio_horizon_s;
  if (!evaluate(short_horizon, &s->sampled_trio_horizon)) return false;
  sampled.dt_s = s->fine_dt_s;
  if (!evaluate(sampled, &s->sampled_fine)) return false;
  for (const auto& p : PolynomialRoots(stepper.tf.den))
    s->fastest_plant_pole_re = std::min(s->fastest_plant_pole_re, p.real());
  return true;
}

// The stepper motor on the sampled loop (the LCM trio's loop).
void RenderSampledSection(std::ostream& os, const SampledSection& s) {
  os << "## Stepper motor on the sampled loop (the LCM trio's loop)\n\n"
     << "The paper's Table IV Nelder-Mead gains (" << Gains(s.gains)
     << ") on the lockstep sampled loop the process trio runs (discrete PID, ZOH plant, dt = "
     << Num(s.dt_s, 5) << " s) against the continuous loop. Sampled metrics use every step of the loop.\n\n";
  RenderSampledTable(os, s);
  RenderTrioNote(os, s);
  RenderSampledDiscussion(os, s);
}

}  // namespace pidlab::report
