#include "pidlab/evaluation/closed_loop.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <vector>

namespace pidlab::evaluation {
namespace {

// |x / step - round(x / step)| small: x is a whole multiple of step.
bool IsMultiple(double x, double step, long* count) {
  const double ratio = x / step;
  const double r = std::round(ratio);
  if (std::abs(ratio - r) > 1e-9 * std::max(1.0, r)) return false;
  *count = static_cast<long>(r);
  return true;
}

}  // namespace

bool ParseLoopKind(const std::string& s, LoopKind* kind) {
  if (s == "continuous")
    *kind = LoopKind::kContinuous;
  else if (s == "sampled")
    *kind = LoopKind::kSampled;
  else
    return false;
  return true;
}

std::string ToString(LoopKind kind) { return kind == LoopKind::kContinuous ? "continuous" : "sampled"; }

// A field added to these structs must join LoopOptionsKey.
static_assert(sizeof(PidOptions) == 10 * 8);
static_assert(sizeof(DisturbanceOptions) == 10 * 8);
static_assert(sizeof(MeasurementNoise) == 3 * 8);
static_assert(sizeof(EpisodeShape) ==
              4 * 8 + sizeof(PidOptions) + sizeof(DisturbanceOptions) + sizeof(MeasurementNoise));
static_assert(sizeof(LoopOptions) == sizeof(EpisodeShape) + 4 * 8);

namespace {
double Bits(std::uint64_t v) {
  double d;
  std::memcpy(&d, &v, sizeof d);
  return d;
}
}  // namespace

std::vector<double> LoopOptionsKey(const LoopOptions& o) {
  const PidOptions& p = o.pid;
  const DisturbanceOptions& d = o.disturbance;
  const MeasurementNoise& n = o.measurement_noise;
  return {o.dt_s,
          o.sample_time_s,
          o.horizon_s,
          o.reference,
          p.dt_s,
          p.derivative_filter_s,
          p.output_min,
          p.output_max,
          static_cast<double>(p.anti_windup),
          p.back_calculation_gain,
          static_cast<double>(p.integral),
          p.setpoint_weight_b,
          p.setpoint_weight_c,
          p.setpoint_filter_s,
          static_cast<double>(d.kind),
          d.amplitude,
          d.period_s,
          d.phase_s,
          d.step_time_s,
          d.noise_hold_s,
          Bits(d.seed),
          d.chirp_f0_hz,
          d.chirp_f1_hz,
          d.chirp_duration_s,
          n.sigma,
          Bits(n.seed),
          n.resolution,
          static_cast<double>(o.loop),
          o.derivative_filter_ratio,
          o.derivative_filter_min_s,
          o.stability_margin};
}

bool LoopOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  long count = 0;
  // Ratios are compared with the limits as doubles before any conversion.
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s))
    os << "sample time " << sample_time_s << " s must be positive and finite";
  else if (!(horizon_s > 0.0) || !std::isfinite(horizon_s))
    os << "horizon " << horizon_s << " s must be positive and finite";
  else if (horizon_s / sample_time_s > kMaxLoopSamples + 0.5)
    os << "horizon / sample time = " << horizon_s / sample_time_s << " samples is more than 1e7";
  else if (!IsMultiple(horizon_s, sample_time_s, &count) || count < 1)
    os << "horizon " << horizon_s << " s must be a whole multiple of the sample time " << sample_time_s
       << " s";
  else if (!std::isfinite(reference) || reference == 0.0 || std::abs(reference) > kMaxCoefficientMagnitude)
    os << "reference " << reference << " must be finite, nonzero and at most " << kMaxCoefficientMagnitude
       << " in magnitude";
  else if (!(stability_margin >= 0.0) || !(stability_margin < 1.0))
    os << "stability margin " << stability_margin << " must be in [0, 1)";
  else if (!(dt_s > 0.0) || !std::isfinite(dt_s))  // a bad --dt is an error even if the loop ignores it
    os << "dt " << dt_s << " s must be positive and finite";
  else if (!(derivative_filter_ratio >= 0.0) || !std::isfinite(derivative_filter_ratio))
    os << "derivative filter ratio " << derivative_filter_ratio << " must be >= 0 and finite";
  else if (!(derivative_filter_min_s >= 0.0) || !std::isfinite(derivative_filter_min_s))
    os << "derivative filter floor " << derivative_filter_min_s << " s must be >= 0 and finite";
  else if (derivative_filter_ratio > 0.0 && pid.derivative_filter_s != 0.0)
    os << "give the derivative filter once: a time constant " << pid.derivative_filter_s << " s or a ratio "
       << derivative_filter_ratio << ", not both";
  else if (!(pid.derivative_filter_s >= 0.0) || !std::isfinite(pid.derivative_filter_s))
    os << "derivative filter " << pid.derivative_filter_s << " s must be >= 0 and finite";
  else if (!disturbance.IsValid(error) || !measurement_noise.IsValid(error))
    return false;
  else if (loop == LoopKind::kContinuous && disturbance.kind == DisturbanceKind::kChirp)
    os << "disturbance chirp: the continuous loop cannot integrate a chirp exactly (its exosystem holds "
          "constants and sines), use --loop sampled";
  else if (loop == LoopKind::kContinuous && measurement_noise.sigma != 0.0)
    os << "measurement noise " << measurement_noise.sigma
       << ": noise on the measured y needs the sampled loop, use --loop sampled";
  else if (loop == LoopKind::kContinuous && measurement_noise.resolution != 0.0)
    os << "measurement resolution " << measurement_noise.resolution
       << ": a quantised measured y needs the sampled loop, use --loop sampled";
  else if (loop == LoopKind::kSampled && disturbance.kind == DisturbanceKind::kChirp &&
           !(disturbance.chirp_f1_hz < 0.5 / dt_s))
    os << "chirp band " << disturbance.chirp_f0_hz << "," << disturbance.chirp_f1_hz
       << " Hz: F1 must be below the Nyquist frequency 1/(2 dt) = " << 0.5 / dt_s << " Hz";
  else if (loop == LoopKind::kContinuous && DisturbanceBreakpoints() > kMaxDisturbanceBreakpoints)
    os << "the " << ToString(disturbance.kind) << " disturbance switches " << DisturbanceBreakpoints()
       << " times within the horizon of the continuous loop, more than 1e6: use a longer period or noise "
          "hold";
  else if (loop == LoopKind::kSampled) {
    const PidOptions p = Pid();
    if (horizon_s / dt_s > kMaxLoopSteps + 0.5)
      os << "horizon " << horizon_s << " s / dt " << dt_s << " s = " << horizon_s / dt_s
         << " steps is more than 5e7";
    else if (!IsMultiple(sample_time_s, dt_s, &count) || count < 1)
      os << "sample time " << sample_time_s << " s must be a whole multiple of dt " << dt_s << " s";
    else if (!p.IsValid(error))
      return false;
    else
      return true;
  } else {
    return true;
  }
  if (error) *error = os.str();
  return false;
}

int LoopOptions::NumSamples() const { return static_cast<int>(std::lround(horizon_s / sample_time_s)) + 1; }
int LoopOptions::StepsPerSample() const { return static_cast<int>(std::lround(sample_time_s / dt_s)); }
long LoopOptions::TotalSteps() const { return std::lround(horizon_s / dt_s); }

double LoopOptions::DisturbanceBreakpoints() const {
  switch (disturbance.kind) {
    case DisturbanceKind::kSquare:
      return std::floor(horizon_s / (disturbance.period_s / 2.0)) + 1.0;
    case DisturbanceKind::kNoise:
    case DisturbanceKind::kPrbs:
      return std::floor(horizon_s / disturbance.noise_hold_s) + 1.0;
    case DisturbanceKind::kStep:
      return 1.0;
    case DisturbanceKind::kNone:
    case DisturbanceKind::kSine:
    case DisturbanceKind::kChirp:
      break;
  }
  return 0.0;
}

double LoopOptions::StepsPerEvaluation() const {
  if (loop == LoopKind::kSampled) return horizon_s / dt_s;
  return horizon_s / sample_time_s + 1.0 + kStepsPerBreakpoint * DisturbanceBreakpoints();
}

std::vector<int> LiveLoopStates(const ContinuousClosedLoop<double>& loop) {
  // With ki = 0 the integrator state z never reaches u (with kd = 0 the
  // filter state v neither): its pole is a hidden mode of the realisation,
  // not of the loop.
  const int order = loop.loop_order();
  std::vector<int> live;
  for (int j = 0; j < order; ++j) {
    bool feeds = j < loop.plant_order;
    for (int i = 0; i < order && !feeds; ++i)
      if (i != j && loop.m(i, j) != 0.0) feeds = true;
    if (feeds) live.push_back(j);
  }
  return live;
}

int EffectiveLoopOrder(const ContinuousClosedLoop<double>& loop) {
  return static_cast<int>(LiveLoopStates(loop).size());
}

Eigen::MatrixXd LiveLoopMatrix(const ContinuousClosedLoop<double>& loop) {
  const std::vector<int> live = LiveLoopStates(loop);
  const int n = static_cast<int>(live.size());
  Eigen::MatrixXd m(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) m(i, j) = loop.m(live[i], live[j]);
  return m;
}

Stability ContinuousStability(const ContinuousClosedLoop<double>& loop, double margin) {
  Eigen::MatrixXd m = LiveLoopMatrix(loop);
  const int n = static_cast<int>(m.rows());
  BalanceInPlace(&m);
  Eigen::EigenSolver<Eigen::MatrixXd> es(m, false);
  Stability s;
  s.abscissa = -std::numeric_limits<double>::infinity();
  bool ok = es.info() == Eigen::Success;
  for (int i = 0; i < n && es.info() == Eigen::Success; ++i) {  // every pole, even past an unstable one
    const std::complex<double> p = es.eigenvalues()(i);
    s.poles.push_back(p);
    s.abscissa = std::max(s.abscissa, p.real());
    if (!std::isfinite(p.real()) || !(p.real() < -margin * std::max(1.0, std::abs(p)))) ok = false;
  }
  s.stable = ok && static_cast<int>(s.poles.size()) == n;
  std::sort(s.poles.begin(), s.poles.end(), [](const auto& a, const auto& b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
  return s;
}

namespace {

// DelayIsValid() with the refusal's message in *error.
bool DelayIsValidOrExplain(const Plant& plant, const LoopOptions& o, const std::string& name,
                           std::string* error) {
  const double l = plant.delay_s;
  std::ostringstream os;
  if (!std::isfinite(l) || !(l >= 0.0) || !(l <= kMaxDelaySeconds))
    os << name << " " << l << " s must be >= 0, finite and at most " << kMaxDelaySeconds << " s";
  else if (l == 0.0)
    return true;
  else if (plant.nonlinear)
    os << name << " " << l << " s: plant " << plant.name << " with dead time is not supported yet";
  else if (o.loop == LoopKind::kContinuous)
    return true;  // the method of steps (delayed_loop.h); a neutral loop is refused with the gains
  else if (!(o.dt_s > 0.0) || !std::isfinite(o.dt_s))
    os << "dt " << o.dt_s << " s must be positive and finite";
  else if (l / o.dt_s > 2.0 * static_cast<double>(kMaxAnalysedDelaySteps) ||
           SplitDelay(l, o.dt_s).steps > kMaxAnalysedDelaySteps)  // d = ceil(L / dt) as the plant counts it
    os << name << " " << l << " s at dt " << o.dt_s << " s needs ceil(L / dt) = " << std::ceil(l / o.dt_s)
       << " stored inputs, more than the " << kMaxAnalysedDelaySteps
       << " the sampled loop's stability analysis takes: use a larger dt";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

}  // namespace

Status DelayIsValid(const Plant& plant, const LoopOptions& o, const std::string& name) {
  std::string why;
  if (!DelayIsValidOrExplain(plant, o, name, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

DiscretePlant SampledPlant(const Plant& plant, double dt_s) {
  return DiscretePlant(plant.tf, dt_s, plant.delay_s);
}

PidStatus RunNonlinearSampledLoop(NonlinearStepperPlant* plant, const PidGains& gains,
                                  const PidOptions& pid_options, const Disturbance& disturbance,
                                  long total_steps, int steps_per_sample, std::vector<double>* y_samples,
                                  std::vector<SampledStep>* trajectory, double reference,
                                  const MeasurementNoise& noise) {
  DiscretePid<double> pid(gains, pid_options);
  plant->Reset();
  const double dt = pid_options.dt_s;
  y_samples->clear();
  y_samples->reserve(static_cast<std::size_t>(total_steps / steps_per_sample + 1));
  PidStatus status = PidStatus::kOk;
  for (long k = 0;; ++k) {
    const double y = noise.Measured(plant->Output(), k);
    if (k % steps_per_sample == 0) y_samples->push_back(y);
    if (k == total_steps) break;
    const double t = static_cast<double>(k) * dt;
    const double n = disturbance.Value(t);
    double u = 0.0;
    const PidStatus s = pid.Step(reference, y, &u);
    if (s != PidStatus::kOk && s != PidStatus::kSaturated) status = s;
    if (trajectory) trajectory->push_back({k, t, reference, y, u, n});
    plant->Step(u + n);
  }
  return status;
}

}  // namespace pidlab::evaluation
