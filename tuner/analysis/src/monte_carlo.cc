// Parametric robustness by Monte Carlo (monte_carlo.h).

#include "pidlab/analysis/monte_carlo.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

namespace pidlab::analysis {

using plant_sim::ModelFromValues;
using plant_sim::ParametersAreValid;
using plant_sim::ProcessModel;
using plant_sim::ProcessModelUncertainty;

namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// u in [-1, 1) from 53 bits of the generator: the same on every platform.
double Uniform(std::mt19937_64* rng) { return 2.0 * static_cast<double>((*rng)() >> 11) * 0x1.0p-53 - 1.0; }

// A standard normal by Box-Muller from two 53-bit uniforms (u1 in (0, 1]), so
// that the draws do not depend on the standard library's distributions.
double StandardNormal(std::mt19937_64* rng) {
  const double u1 = static_cast<double>(((*rng)() >> 11) + 1) * 0x1.0p-53;
  const double u2 = static_cast<double>((*rng)() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586476925 * u2);
}

// A square root S of the covariance, S S^T = C: its Cholesky factor, or, for
// a matrix that is only semi-definite (a parameter the data did not move),
// V sqrt(max(D, 0)) from its eigendecomposition.
Eigen::MatrixXd CovarianceRoot(const ProcessModelUncertainty& m) {
  const auto p = static_cast<Eigen::Index>(m.values.size());
  const Eigen::MatrixXd c =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          m.covariance.data(), p, p);
  const Eigen::LLT<Eigen::MatrixXd> llt(c);
  if (llt.info() == Eigen::Success) return llt.matrixL();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

// The plants of a model's draws: parameter vectors from N(values,
// covariance), each redrawn while it is not a model's (ParametersAreValid)
// up to kMaxModelRedraws times; a draw that never is has an empty tf.
std::vector<Plant> DrawModelPlants(const Plant& nominal, const MonteCarloOptions& o, int* redrawn) {
  const ProcessModelUncertainty& m = *nominal.model;
  const Eigen::MatrixXd root = CovarianceRoot(m);
  const auto p = static_cast<Eigen::Index>(m.values.size());
  const Eigen::VectorXd mean = Eigen::Map<const Eigen::VectorXd>(m.values.data(), p);
  std::mt19937_64 rng(o.seed);
  std::vector<Plant> plants;
  plants.reserve(static_cast<std::size_t>(o.samples));
  for (int i = 0; i < o.samples; ++i) {
    Plant plant;
    plant.name = nominal.name;
    for (int attempt = 0; attempt <= kMaxModelRedraws; ++attempt) {
      if (attempt > 0) ++*redrawn;
      Eigen::VectorXd z(p);
      for (Eigen::Index k = 0; k < p; ++k) z(k) = StandardNormal(&rng);
      const Eigen::VectorXd x = mean + root * z;
      const std::vector<double> values(x.data(), x.data() + p);
      // A tf's draws are its coefficients and Td, redrawn while the
      // denominator is not stable (ParametersAreValid).
      if (!ParametersAreValid(m.kind, values, nullptr, m.poles, m.zeros)) continue;
      const ProcessModel model = ModelFromValues(m.kind, values, m.poles, m.zeros);
      TransferFunction tf = model.ToTransferFunction();
      if (!tf.IsValid(nullptr)) continue;
      plant.tf = std::move(tf);
      plant.delay_s = model.delay_s();
      break;
    }
    plants.push_back(plant);
  }
  return plants;
}

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
    d.min = d.median = d.p95 = d.max = kNoValue;
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

std::string PerturbedText(const Plant& nominal, const StepperMotorParameters* stepper) {
  if (DrawsFromCovariance(nominal)) return kCovariancePerturbed;
  if (nominal.model)
    return "transfer-function coefficients (the identified model's covariance is not ok: " +
           (nominal.model->covariance_message.empty() ? std::string("none given")
                                                      : nominal.model->covariance_message) +
           ")";
  return stepper ? "Table I parameters" : "transfer-function coefficients";
}

std::vector<Plant> DrawPlants(const Plant& nominal, const StepperMotorParameters* stepper,
                              const MonteCarloOptions& o, int* redrawn) {
  int redrawn_here = 0;
  if (!redrawn) redrawn = &redrawn_here;
  *redrawn = 0;
  if (DrawsFromCovariance(nominal)) return DrawModelPlants(nominal, o, redrawn);
  std::mt19937_64 rng(o.seed);
  std::vector<Plant> plants;
  plants.reserve(static_cast<std::size_t>(o.samples));
  for (int i = 0; i < o.samples; ++i) {
    Plant p;
    p.name = nominal.name;
    // The coefficients' draws keep the dead time (only a model's is drawn).
    p.delay_s = nominal.delay_s;
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

namespace {

// RunMonteCarlo() with the refusal's message in *error.
bool RunMonteCarloOrExplain(const Plant& nominal, const StepperMotorParameters* stepper,
                            const PidGains& gains, const evaluation::LoopOptions& options,
                            const MonteCarloOptions& mc, MonteCarloSummary* summary, std::string* error,
                            const std::function<void(int, int)>& progress) {
  if (!mc.IsValid(error)) return false;
  if (!nominal.tf.IsValid(error) || nominal.tf.den.empty()) return false;
  if (nominal.delay_s != 0.0 && !nominal.model) {
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
  if (const Status st = evaluation::Evaluate(nominal, gains, options, what, &nominal_ev); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  *summary = MonteCarloSummary();
  summary->samples = mc.samples;
  summary->perturbed = PerturbedText(nominal, stepper);
  LoopAnalysisOptions ao;
  ao.points_per_decade = 50.0;
  std::vector<double> iae, overshoot, ms;
  const std::vector<Plant> plants = DrawPlants(nominal, stepper, mc, &summary->redrawn);
  for (std::size_t i = 0; i < plants.size(); ++i) {
    const Plant& p = plants[i];
    evaluation::Evaluation ev;
    LoopAnalysis a;
    if (p.tf.den.empty()) {
      ++summary->invalid;
    } else if (evaluation::Evaluate(p, gains, options, what, &ev).ok() && ev.stability.stable &&
               AnalyzeLoop(p, gains, options, ao, &a).ok()) {
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

}  // namespace

Status RunMonteCarlo(const Plant& nominal, const StepperMotorParameters* stepper, const PidGains& gains,
                     const evaluation::LoopOptions& options, const MonteCarloOptions& mc,
                     MonteCarloSummary* summary, const std::function<void(int, int)>& progress) {
  std::string why;
  if (!RunMonteCarloOrExplain(nominal, stepper, gains, options, mc, summary, &why, progress))
    return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::analysis
