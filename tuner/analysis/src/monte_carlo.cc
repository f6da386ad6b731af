// Parametric robustness by Monte Carlo (monte_carlo.h).

#include "pidlab/analysis/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

namespace pidlab::analysis {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// u in [-1, 1) from 53 bits of the generator: the same on every platform.
double Uniform(std::mt19937_64* rng) { return 2.0 * static_cast<double>((*rng)() >> 11) * 0x1.0p-53 - 1.0; }

}  // namespace

bool MonteCarloOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (samples < 1 || samples > 100000)
    os << "Monte Carlo samples " << samples << " must be in [1, 100000]";
  else if (!(spread >= 0.0) || !(spread < 1.0))
    os << "spread " << spread << " must be in [0, 1) (0.1 = 10 %)";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

Distribution Summarize(std::vector<double> v) {
  Distribution d;
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  d.count = static_cast<int>(v.size());
  if (v.empty()) {
    d.min = d.median = d.p95 = d.max = kNaN;
    return d;
  }
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  d.min = v.front();
  d.max = v.back();
  d.median = n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(n)));
  d.p95 = v[std::max<std::size_t>(rank, 1) - 1];
  return d;
}

std::vector<Plant> DrawPlants(const Plant& nominal, const StepperMotorParameters* stepper,
                              const MonteCarloOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::vector<Plant> plants;
  plants.reserve(static_cast<std::size_t>(o.samples));
  for (int i = 0; i < o.samples; ++i) {
    Plant p;
    p.name = nominal.name;
    if (stepper) {
      StepperMotorParameters s = *stepper;
      for (double* f :
           {&s.resistance_ohm, &s.self_inductance_h, &s.mutual_inductance_h, &s.inertia_kg_m2, &s.rotor_teeth,
            &s.viscous_friction, &s.tooth_pitch_rad, &s.stationary_current_a, &s.flux_linkage})
        *f *= 1.0 + o.spread * Uniform(&rng);
      std::string error;
      if (s.IsValid(&error)) {
        p.tf = StepperMotorTransferFunction(s);
        if (!p.tf.IsValid(&error)) p.tf = TransferFunction{};
      }
    } else {
      const double lead = nominal.tf.den.front();
      for (double c : nominal.tf.num) p.tf.num.push_back(c / lead * (1.0 + o.spread * Uniform(&rng)));
      p.tf.den.push_back(1.0);
      for (std::size_t k = 1; k < nominal.tf.den.size(); ++k)
        p.tf.den.push_back(nominal.tf.den[k] / lead * (1.0 + o.spread * Uniform(&rng)));
      std::string error;
      if (!p.tf.IsValid(&error)) p.tf = TransferFunction{};
    }
    plants.push_back(p);
  }
  return plants;
}

bool RunMonteCarlo(const Plant& nominal, const StepperMotorParameters* stepper, const PidGains& gains,
                   const evaluation::LoopOptions& options, const MonteCarloOptions& mc,
                   MonteCarloSummary* summary, std::string* error,
                   const std::function<void(int, int)>& progress) {
  if (!mc.IsValid(error)) return false;
  if (!nominal.tf.IsValid(error) || nominal.tf.den.empty()) return false;
  if (nominal.delay_s != 0.0) {
    // Each draw needs the loop's time response (IAE, overshoot) and, sampled,
    // the analysis; neither exists yet with dead time.
    std::ostringstream os;
    os << "dead time " << nominal.delay_s
       << " s: the Monte Carlo analysis with dead time is not supported yet";
    if (error) *error = os.str();
    return false;
  }
  // The nominal plant's errors are the caller's (bad input), found up front.
  evaluation::Evaluation nominal_ev;
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  what.compute_step_info = mc.overshoot;
  if (!evaluation::Evaluate(nominal, gains, options, what, &nominal_ev, error)) return false;
  *summary = MonteCarloSummary();
  summary->samples = mc.samples;
  summary->perturbed = stepper ? "Table I parameters" : "transfer-function coefficients";
  LoopAnalysisOptions ao;
  ao.points_per_decade = 50.0;
  std::vector<double> iae, overshoot, ms;
  const std::vector<Plant> plants = DrawPlants(nominal, stepper, mc);
  for (std::size_t i = 0; i < plants.size(); ++i) {
    const Plant& p = plants[i];
    evaluation::Evaluation ev;
    LoopAnalysis a;
    if (p.tf.den.empty()) {
      ++summary->invalid;
    } else if (evaluation::Evaluate(p, gains, options, what, &ev, nullptr) && ev.stability.stable &&
               AnalyzeLoop(p, gains, options, ao, &a, nullptr)) {
      ++summary->stable;
      iae.push_back(ev.iae);
      if (ev.step.valid) overshoot.push_back(ev.step.overshoot_pct);
      ms.push_back(a.ms);
    }
    if (progress) progress(static_cast<int>(i) + 1, mc.samples);
  }
  summary->stable_fraction = static_cast<double>(summary->stable) / mc.samples;
  summary->iae = Summarize(iae);
  summary->overshoot_pct = Summarize(overshoot);
  summary->ms = Summarize(ms);
  return true;
}

}  // namespace pidlab::analysis
