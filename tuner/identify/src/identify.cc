// The fit of identify.h. The parameters Ceres sees, theta, are in the order
// of ParameterNames: Kp free, every time constant (Tp1, Tp2, Tw) as its
// logarithm (positive, and scaled alike whatever its size), Zeta bounded to
// (0, 1) and Td bounded to [0, max_delay_fraction of the record]. The delay
// stays continuous: DiscretePlant splits it over the sample exactly, so the
// cost is a continuous function of Td and central differences see it. A
// TF's coefficients are free (tf_start.h; docs/identify.md, "A general
// transfer function").

#include "pidlab/identify/identify.h"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "arx_start.h"
#include "pidlab/optim/sobol.h"
#include "pidlab/plant_sim/discrete_plant.h"
#include "piecewise_response.h"
#include "tf_start.h"

namespace pidlab::identify {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Bounds of Zeta inside (0, 1).
constexpr double kMinZeta = 1e-3;
constexpr double kMaxZeta = 1.0 - 1e-9;
// How far the time constants may go from the record's scales: [dt / 1000, 1000 T_record].
constexpr double kTimeConstantRange = 1e3;

// What every start's problem shares: the record without its operating point.
struct Record {
  ProcessModelKind kind;
  int poles = 0, zeros = 0;  // TF only
  std::vector<double> du, dy;
  double dt_s = 0.0, length_s = 0.0, max_delay_s = 0.0;
  /// The sample times. `piecewise`: simulated interval by interval
  /// (piecewise_response.h; non-uniform sampling, a first-order hold or an
  /// initial condition other than zero), else DiscretePlant over dt_s.
  std::vector<double> t;
  bool piecewise = false;
  Intersample hold = Intersample::kZoh;
  InitialCondition initial = InitialCondition::kZero;
  /// The output offset is a parameter too: theta[p] is added to y0.
  bool offset = false;
  /// The input offset is a parameter too (after the output offset, if any):
  /// it is added to u0, so the model's input is du - it.
  bool input_offset = false;
};

int ParameterCount(const Record& record) {
  return static_cast<int>(ParameterNames(record.kind, record.poles, record.zeros).size());
}
// Ceres's parameter block: the model's parameters, then the offset if estimated.
int BlockSize(const Record& record) {
  return ParameterCount(record) + (record.offset ? 1 : 0) + (record.input_offset ? 1 : 0);
}
int InputOffsetIndex(const Record& record) { return ParameterCount(record) + (record.offset ? 1 : 0); }
double InputOffsetOf(const Record& record, const double* theta) {
  return record.input_offset ? theta[InputOffsetIndex(record)] : 0.0;
}
double OffsetOf(const Record& record, const double* theta) {
  return record.offset ? theta[ParameterCount(record)] : 0.0;
}

// The initial state's entries fitted by projection (kEstimate): parameters
// too, for the degrees of freedom and the AIC.
int FittedStates(const Record& record, const ProcessModel& model) {
  return record.initial == InitialCondition::kEstimate ? internal::ModelOrder(model) : 0;
}

// theta[i] is the logarithm of a time constant.
bool IsLogParameter(const Record& record, int i) {
  const int p = ParameterCount(record);
  const ProcessModelKind kind = record.kind;
  return kind != ProcessModelKind::kTf && i > 0 && i < p - 1 &&
         !(kind == ProcessModelKind::kP2DU && i == 2) && !(kind == ProcessModelKind::kP2DZ && i == 3);
}

// theta[i] is P2DZ's Tz (any sign).
bool IsZeroParameter(ProcessModelKind kind, int i) { return kind == ProcessModelKind::kP2DZ && i == 3; }

ProcessModel ModelOf(const Record& record, const double* theta) {
  const int p = ParameterCount(record);
  std::vector<double> values(static_cast<std::size_t>(p));
  for (int i = 0; i < p; ++i)
    values[static_cast<std::size_t>(i)] = IsLogParameter(record, i) ? std::exp(theta[i]) : theta[i];
  // A central difference at the bound Td = 0 looks just below it.
  values.back() = std::max(0.0, values.back());
  if (record.kind == ProcessModelKind::kTf) internal::SnapTinyCoefficients(&values);
  return ModelFromValues(record.kind, values, record.poles, record.zeros);
}

// The response from the record's initial condition; with kEstimate and
// `project`, the free response that best fits dy - offset added (its state
// in *state).
std::vector<double> Simulate(const ProcessModel& model, const Record& record, double offset,
                             double input_shift, bool project, std::vector<double>* state) {
  if (!record.piecewise) return SimulateModel(model, record.du, input_shift, record.dt_s);
  std::vector<double> shifted;  // a copy only when there is a shift to take off
  if (input_shift != 0.0) {
    shifted = record.du;
    for (double& v : shifted) v -= input_shift;
  }
  const std::vector<double>& du = input_shift != 0.0 ? shifted : record.du;
  internal::PiecewiseStart start;
  start.input_before = record.initial == InitialCondition::kZero ? 0.0 : du[0];
  if (record.initial == InitialCondition::kSteadyState && !internal::SteadyState(model, du[0], &start.state))
    throw std::invalid_argument("no steady state");
  std::vector<double> yhat = internal::SimulatePiecewise(model, record.t, du, record.hold, start);
  if (record.initial == InitialCondition::kEstimate && project) {
    std::vector<double> target(record.dy);
    for (double& v : target) v -= offset;
    start.state = internal::FitInitialState(model, record.t, record.hold, target, &yhat);
  }
  if (state) *state = start.state;
  return yhat;
}

// yhat of the model, false if it is not a valid plant or diverges (or, for
// a TF, not admissible: tf_start.h). `offset`, `project`, `state`: Simulate's.
bool TrySimulate(const ProcessModel& model, const Record& record, std::vector<double>* yhat,
                 double offset = 0.0, double input_shift = 0.0, bool project = true,
                 std::vector<double>* state = nullptr) {
  if (model.kind == ProcessModelKind::kTf && !internal::TfDenominatorIsAdmissible(model.a, record.dt_s))
    return false;
  try {
    *yhat = Simulate(model, record, offset, input_shift, project, state);
  } catch (const std::exception&) {
    return false;
  }
  for (double v : *yhat)
    if (!std::isfinite(v)) return false;
  return true;
}

struct OutputError {
  const Record* record;
  bool operator()(double const* const* parameters, double* residuals) const {
    std::vector<double> yhat;
    const double offset = OffsetOf(*record, parameters[0]);
    if (!TrySimulate(ModelOf(*record, parameters[0]), *record, &yhat, offset,
                     InputOffsetOf(*record, parameters[0])))
      return false;
    for (std::size_t k = 0; k < yhat.size(); ++k) residuals[k] = record->dy[k] - offset - yhat[k];
    return true;
  }
};

// The problem over one parameter block `theta`, with its bounds.
void BuildProblem(const Record& record, double* theta, ceres::Problem* problem) {
  auto* cost =
      new ceres::DynamicNumericDiffCostFunction<OutputError, ceres::CENTRAL>(new OutputError{&record});
  const int p = ParameterCount(record);
  cost->AddParameterBlock(BlockSize(record));
  cost->SetNumResiduals(static_cast<int>(record.dy.size()));
  problem->AddResidualBlock(cost, nullptr, theta);
  for (int i = 1; i < p - 1 && record.kind != ProcessModelKind::kTf; ++i) {
    if (IsLogParameter(record, i)) {
      problem->SetParameterLowerBound(theta, i, std::log(record.dt_s / kTimeConstantRange));
      problem->SetParameterUpperBound(theta, i, std::log(record.length_s * kTimeConstantRange));
    } else if (IsZeroParameter(record.kind, i)) {
      problem->SetParameterLowerBound(theta, i, -record.length_s * kTimeConstantRange);
      problem->SetParameterUpperBound(theta, i, record.length_s * kTimeConstantRange);
    } else {
      problem->SetParameterLowerBound(theta, i, kMinZeta);
      problem->SetParameterUpperBound(theta, i, kMaxZeta);
    }
  }
  problem->SetParameterLowerBound(theta, p - 1, 0.0);
  problem->SetParameterUpperBound(theta, p - 1, record.max_delay_s);
}

// Kp by linear least squares at the other parameters of *theta: the model is
// linear in it. Left at 1 if the model cannot be simulated. A TF's numerator
// likewise (tf_start.h).
void SetGainByLeastSquares(const Record& record, std::vector<double>* theta) {
  if (record.kind == ProcessModelKind::kTf) {
    internal::SetNumeratorByLeastSquares(record.poles, record.zeros, record.du, record.dy, record.dt_s,
                                         record.offset, theta);
    return;
  }
  const int p = ParameterCount(record);
  (*theta)[0] = 1.0;
  if (record.offset) (*theta)[static_cast<std::size_t>(p)] = 0.0;
  std::vector<double> g;
  // Without the estimated initial state's projection, which is not linear in Kp.
  if (!TrySimulate(ModelOf(record, theta->data()), record, &g, 0.0, InputOffsetOf(record, theta->data()),
                   false))
    return;
  // dy ~ Kp g + offset: the normal equations of one or two unknowns.
  const double n = static_cast<double>(g.size());
  double gy = 0.0, gg = 0.0, sg = 0.0, sy = 0.0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    gy += g[k] * record.dy[k];
    gg += g[k] * g[k];
    sg += g[k];
    sy += record.dy[k];
  }
  if (!record.offset) {
    if (gg > 0.0 && std::isfinite(gy / gg)) (*theta)[0] = gy / gg;
    return;
  }
  const double det = gg * n - sg * sg;
  if (!(det > 1e-12 * gg * n)) return;
  const double kp = (gy * n - sg * sy) / det, offset = (gg * sy - sg * gy) / det;
  if (std::isfinite(kp) && std::isfinite(offset)) {
    (*theta)[0] = kp;
    (*theta)[static_cast<std::size_t>(p)] = offset;
  }
}

// Start `index` of the design: time constants log-spaced over [dt/2, T/2],
// Zeta over [0.1, 0.9], Td over [0, min(max delay, T/4)], by the points of a
// Sobol' sequence (optim/sobol.h, as the tuner's multi-start), digitally
// shifted by the seed unless it is 0; Kp then by linear least squares, the
// model being linear in it.
std::vector<double> StartPoint(const Record& record, const optim::SobolSequence& sobol, int index) {
  const int p = ParameterCount(record);
  std::vector<double> theta(static_cast<std::size_t>(BlockSize(record)), 0.0);
  const double lo = std::log(0.5 * record.dt_s), hi = std::log(0.5 * record.length_s);
  const Eigen::VectorXd h = sobol.Point(static_cast<std::uint32_t>(index));
  if (record.kind == ProcessModelKind::kTf) {
    const std::vector<double> taus =
        internal::SpreadLags(record.poles, h[0], record.poles > 1 ? h[1] : 0.0, lo, hi);
    internal::SetDenominatorFromLags(record.zeros, taus, &theta);
    theta[static_cast<std::size_t>(p - 1)] =
        h[h.size() - 1] * std::min(record.max_delay_s, 0.25 * record.length_s);
    SetGainByLeastSquares(record, &theta);
    return theta;
  }
  for (int i = 1; i < p; ++i) {
    const double hi_coordinate = h[i - 1];
    if (i == p - 1)
      theta.back() = hi_coordinate * std::min(record.max_delay_s, 0.25 * record.length_s);
    else if (IsLogParameter(record, i))
      theta[static_cast<std::size_t>(i)] = lo + hi_coordinate * (hi - lo);
    else if (IsZeroParameter(record.kind, i))
      theta[static_cast<std::size_t>(i)] = (2.0 * hi_coordinate - 1.0) * 0.1 * record.length_s;
    else
      theta[static_cast<std::size_t>(i)] = 0.1 + 0.8 * hi_coordinate;
  }
  SetGainByLeastSquares(record, &theta);
  return theta;
}

// The output-error cost of *theta with Kp set by least squares.
double ScreenCost(const Record& record, std::vector<double>* theta) {
  SetGainByLeastSquares(record, theta);
  std::vector<double> yhat;
  const double offset = OffsetOf(record, theta->data());
  if (!TrySimulate(ModelOf(record, theta->data()), record, &yhat, offset,
                   InputOffsetOf(record, theta->data())))
    return std::numeric_limits<double>::infinity();
  double cost = 0.0;
  for (std::size_t k = 0; k < yhat.size(); ++k)
    cost += 0.5 * (record.dy[k] - offset - yhat[k]) * (record.dy[k] - offset - yhat[k]);
  return cost;
}

// The start from the ARX candidates (arx_start.h) of lowest output-error
// cost, inside the bounds; empty if there is none.
std::vector<double> ArxStartPoint(const Record& record) {
  const int p = ParameterCount(record);
  std::vector<double> best;
  double best_cost = std::numeric_limits<double>::infinity();
  const std::vector<std::vector<double>> candidates =
      record.kind == ProcessModelKind::kTf
          ? internal::TfArxCandidates(record.poles, record.zeros, record.du, record.dy, record.dt_s,
                                      record.max_delay_s)
          : internal::ArxCandidates(record.kind, record.du, record.dy, record.dt_s, record.max_delay_s);
  for (const std::vector<double>& values : candidates) {
    std::vector<double> theta(static_cast<std::size_t>(BlockSize(record)), 0.0);
    for (int i = 1; i < p; ++i) {
      const double v = values[static_cast<std::size_t>(i)];
      if (record.kind == ProcessModelKind::kTf)
        theta[static_cast<std::size_t>(i)] = i == p - 1 ? std::clamp(v, 0.0, record.max_delay_s) : v;
      else if (IsLogParameter(record, i))
        theta[static_cast<std::size_t>(i)] =
            std::clamp(std::log(v), std::log(record.dt_s / kTimeConstantRange),
                       std::log(record.length_s * kTimeConstantRange));
      else if (i == p - 1)
        theta[static_cast<std::size_t>(i)] = std::clamp(v, 0.0, record.max_delay_s);
      else if (IsZeroParameter(record.kind, i))
        theta[static_cast<std::size_t>(i)] = v;
      else
        theta[static_cast<std::size_t>(i)] = std::clamp(v, kMinZeta, kMaxZeta);
    }
    const double cost = ScreenCost(record, &theta);
    if (cost < best_cost) {
      best_cost = cost;
      best = theta;
    }
  }
  return best;
}

// One start's fit; the final cost, or infinity if Ceres failed.
double FitFrom(const Record& record, const IdentifyOptions& options, std::vector<double>* theta) {
  ceres::Problem problem;
  BuildProblem(record, theta->data(), &problem);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-15;
  solver.gradient_tolerance = 1e-20;
  solver.parameter_tolerance = 1e-13;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  // A TF's start may walk to the edge of stability, where a central
  // difference fails and Ceres stops with FAILURE, logged through glog as an
  // error; the start's cost (infinite) says it, so keep glog quiet.
  const int log_level = FLAGS_minloglevel;
  FLAGS_minloglevel = google::GLOG_FATAL;
  ceres::Solve(solver, &problem, &summary);
  FLAGS_minloglevel = log_level;
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(summary.final_cost))
    return std::numeric_limits<double>::infinity();
  return summary.final_cost;
}

// The parameters `held` (indices into theta) held where *theta has them,
// the others refitted from *theta; the cost, or infinity if Ceres failed.
double FitHolding(const Record& record, const IdentifyOptions& options, const std::vector<int>& held,
                  std::vector<double>* theta) {
  ceres::Problem problem;
  BuildProblem(record, theta->data(), &problem);
  problem.SetManifold(theta->data(), new ceres::SubsetManifold(BlockSize(record), held));
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-20;
  solver.parameter_tolerance = 1e-10;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  const int log_level = FLAGS_minloglevel;
  FLAGS_minloglevel = google::GLOG_FATAL;
  ceres::Solve(solver, &problem, &summary);
  FLAGS_minloglevel = log_level;
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(summary.final_cost))
    return std::numeric_limits<double>::infinity();
  return summary.final_cost;
}

// Td held at `td`, the other parameters refitted from *theta.
double FitAtDelay(const Record& record, const IdentifyOptions& options, double td,
                  std::vector<double>* theta) {
  const int p = ParameterCount(record);
  (*theta)[static_cast<std::size_t>(p - 1)] = td;
  return FitHolding(record, options, {p - 1}, theta);
}

// The parameters of *theta at (within 1e-6 of) a bound of the fit, put on
// it: Td at 0 or its maximum, a time constant at dt / 1000 or 1000 times
// the record, Zeta at either end. Not for a TF.
std::vector<int> SnapToBounds(const Record& record, std::vector<double>* theta) {
  std::vector<int> at;
  if (record.kind == ProcessModelKind::kTf) return at;
  const int p = ParameterCount(record);
  for (int i = 1; i < p; ++i) {
    double lo, hi, tolerance = 1e-6;
    if (i == p - 1) {
      lo = 0.0, hi = record.max_delay_s, tolerance = 1e-6 * record.dt_s;
    } else if (IsLogParameter(record, i)) {
      lo = std::log(record.dt_s / kTimeConstantRange), hi = std::log(record.length_s * kTimeConstantRange);
    } else if (!IsZeroParameter(record.kind, i)) {
      lo = kMinZeta, hi = kMaxZeta, tolerance = 1e-6 * kMinZeta;
      if (hi - (*theta)[static_cast<std::size_t>(i)] <= 1e-6) {
        (*theta)[static_cast<std::size_t>(i)] = hi;
        at.push_back(i);
        continue;
      }
    } else {
      continue;
    }
    double& v = (*theta)[static_cast<std::size_t>(i)];
    if (v - lo <= tolerance)
      v = lo;
    else if (hi - v <= tolerance)
      v = hi;
    else
      continue;
    at.push_back(i);
  }
  return at;
}

// A fit that ends with parameters at bounds may have stalled there: Ceres
// projects its steps onto the box, and where two parameters press on their
// bounds the projected steps can fail to lower the cost long before the
// others are optimal. Those parameters held on their bounds, the others
// refitted; replaces *theta and *cost if lower, true then.
bool RefitAtBounds(const Record& record, const IdentifyOptions& options, std::vector<double>* theta,
                   double* cost) {
  std::vector<double> trial = *theta;
  const std::vector<int> held = SnapToBounds(record, &trial);
  if (held.empty()) return false;
  const double c = FitHolding(record, options, held, &trial);
  if (!(c < *cost)) return false;
  *theta = trial;
  *cost = c;
  return true;
}

// The delay's profile around the best fit (*theta, *cost): Td held at 0, at
// half the best Td, at the best Td and at half samples up to a sample on
// either side of it, the rest refitted; from the lowest of those a free fit. The cost is piecewise
// smooth in Td, with kinks where Td crosses a sample, so a start can stop at
// a kink above the optimum, or just short of the bound Td = 0. Replaces
// *theta and *cost if it finds a lower cost; true then.
bool ProfileDelay(const Record& record, const IdentifyOptions& options, std::vector<double>* theta,
                  double* cost) {
  const int p = ParameterCount(record);
  const double best_td = (*theta)[static_cast<std::size_t>(p - 1)];
  std::vector<double> grid = {best_td};
  if (best_td > 0.0) grid.insert(grid.end(), {0.0, 0.5 * best_td});
  for (int k = -2; k <= 2; ++k)
    if (k != 0) grid.push_back(best_td + 0.5 * k * record.dt_s);
  std::vector<double> lowest;
  double lowest_cost = std::numeric_limits<double>::infinity();
  for (double td : grid) {
    // The best Td itself too: held there, the others converge even where
    // the free fit stopped at the bound Td = 0.
    if (td < 0.0 || td > record.max_delay_s) continue;
    std::vector<double> trial = *theta;
    const double c = FitAtDelay(record, options, td, &trial);
    if (c < lowest_cost) {
      lowest_cost = c;
      lowest = trial;
    }
  }
  if (lowest.empty() || !(lowest_cost < *cost)) return false;
  const double polished = FitFrom(record, options, &lowest);
  if (!(polished < *cost)) return false;
  *theta = lowest;
  *cost = polished;
  return true;
}

// The covariance of the parameters at `theta` (of the values, not of theta;
// p x p, row-major) and their standard errors, scaled by the residual
// variance; false with the reason if Ceres cannot invert J'J.
bool Covariance(const Record& record, std::vector<double> theta, double cost, std::vector<double>* errors,
                std::vector<double>* matrix, double* offset_error, double* input_offset_error,
                std::string* message) {
  const int p = ParameterCount(record);
  const int q = BlockSize(record);
  *offset_error = *input_offset_error = kNaN;
  const int n = static_cast<int>(record.dy.size());
  errors->assign(static_cast<std::size_t>(p), kNaN);
  matrix->assign(static_cast<std::size_t>(p * p), kNaN);
  ceres::Problem problem;
  BuildProblem(record, theta.data(), &problem);
  ceres::Covariance::Options covariance_options;
  covariance_options.algorithm_type = ceres::DENSE_SVD;
  covariance_options.num_threads = 1;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> blocks = {{theta.data(), theta.data()}};
  // Ceres logs a rank-deficient J'J through glog as an error on stderr; the
  // result says it in its own words (covariance_message), so keep glog quiet.
  const int log_level = FLAGS_minloglevel;
  FLAGS_minloglevel = google::GLOG_FATAL;
  const bool computed = covariance.Compute(blocks, &problem);
  FLAGS_minloglevel = log_level;
  if (!computed) {
    *message = "Ceres could not compute the covariance (J'J singular or ill-conditioned)";
    return false;
  }
  std::vector<double> full(static_cast<std::size_t>(q * q));
  covariance.GetCovarianceBlock(theta.data(), theta.data(), full.data());
  // The model's block (the offset's row and column left out: the marginal
  // covariance of the model's parameters).
  std::vector<double> c(static_cast<std::size_t>(p * p));
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j)
      c[static_cast<std::size_t>(i * p + j)] = full[static_cast<std::size_t>(i * q + j)];
  const double variance =
      2.0 * cost / std::max(1, n - q - FittedStates(record, ModelOf(record, theta.data())));
  if (record.offset)
    *offset_error = std::sqrt(std::max(0.0, full[static_cast<std::size_t>(p * q + p)] * variance));
  if (record.input_offset) {
    const int i = InputOffsetIndex(record);
    *input_offset_error = std::sqrt(std::max(0.0, full[static_cast<std::size_t>(i * q + i)] * variance));
  }
  const ProcessModel model = ModelOf(record, theta.data());
  const std::vector<double> values = ParameterValues(model);
  // d value / d theta: the value for a logarithm, else 1.
  std::vector<double> d(static_cast<std::size_t>(p));
  for (int i = 0; i < p; ++i)
    d[static_cast<std::size_t>(i)] = IsLogParameter(record, i) ? values[static_cast<std::size_t>(i)] : 1.0;
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j) {
      const auto ij = static_cast<std::size_t>(i * p + j);
      (*matrix)[ij] = c[ij] * variance * d[static_cast<std::size_t>(i)] * d[static_cast<std::size_t>(j)];
    }
  for (int i = 0; i < p; ++i)
    (*errors)[static_cast<std::size_t>(i)] =
        std::sqrt(std::max(0.0, (*matrix)[static_cast<std::size_t>(i * p + i)]));
  return true;
}

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

std::vector<double> SimulateModel(const ProcessModel& model, const std::vector<double>& u, double u0,
                                  double dt_s) {
  DiscretePlant plant(model.ToTransferFunction(), dt_s, model.delay_s());
  std::vector<double> yhat(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    yhat[k] = plant.Output();
    plant.Step(u[k] - u0);
  }
  return yhat;
}

namespace {

// The best of the starts: its theta, and every start's cost.
std::vector<double> MultiStart(const Record& record, const IdentifyOptions& options,
                               const std::vector<std::vector<double>>& nested, std::vector<double>* costs,
                               bool* arx_used) {
  std::vector<double> best;
  double best_cost = std::numeric_limits<double>::infinity();
  const int dimensions = record.kind == ProcessModelKind::kTf ? internal::TfDesignDimensions(record.poles)
                                                              : ParameterCount(record) - 1;
  const optim::SobolSequence sobol =
      options.seed == 0 ? optim::SobolSequence(dimensions) : optim::SobolSequence(dimensions, options.seed);
  int total = options.starts + static_cast<int>(nested.size());
  // held: a nested start's delay (its contained model's) is held while the
  // rest is refitted, then freed. A free fit from there may leave the
  // contained optimum at once where it sits at a kink of the cost in Td (a
  // sample crossing), and stop above the contained model's cost.
  const auto fit = [&](std::vector<double> theta, bool held) {
    double cost = std::numeric_limits<double>::infinity();
    if (held) {
      const int p = ParameterCount(record);
      cost = FitAtDelay(record, options, theta[static_cast<std::size_t>(p - 1)], &theta);
    }
    std::vector<double> freed = theta;
    const double free_cost = FitFrom(record, options, &freed);
    if (!(cost <= free_cost)) {
      cost = free_cost;
      theta = freed;
    }
    costs->push_back(cost);
    if (cost < best_cost) {
      best_cost = cost;
      best = theta;
    }
    if (options.progress) options.progress(record.kind, static_cast<int>(costs->size()), total, best_cost);
  };
  if (options.arx_start) {
    std::vector<double> theta = ArxStartPoint(record);
    *arx_used = !theta.empty();
    total += *arx_used ? 1 : 0;
    if (*arx_used) fit(theta, false);
  }
  for (const std::vector<double>& theta : nested) fit(theta, true);
  for (int s = 0; s < options.starts; ++s) fit(StartPoint(record, sobol, s), false);
  return best;
}

// The model `kind` contains, whose optimum starts `kind`'s fit: P1D in P2D
// (Tp2 -> 0), P2D in P2DU (as long as its lags are near enough to be a
// pair's) and in P2DZ (Tz = 0).
bool ContainedKind(ProcessModelKind kind, ProcessModelKind* inner) {
  if (kind == ProcessModelKind::kP2D)
    *inner = ProcessModelKind::kP1D;
  else if (kind == ProcessModelKind::kP2DU || kind == ProcessModelKind::kP2DZ)
    *inner = ProcessModelKind::kP2D;
  else
    return false;
  return true;
}

// Starts at the optimum `inner` of the model that `record`'s kind contains,
// in Ceres's coordinates (the offsets relative to the record's u0 and y0).
// P2D from P1D twice: a second lag at its lower bound (P1D's optimum as
// nearly as the bound allows: a free fit from a lag just above it can stall
// there, its step projected onto the bound), and one of half a sample taken
// out of the delay (a short lag and a short delay look alike).
std::vector<std::vector<double>> NestedStarts(const Record& record, const IdentifyResult& inner, double u0,
                                              double y0) {
  ProcessModelKind expected;
  if (!ContainedKind(record.kind, &expected) || inner.model.kind != expected) return {};
  const int p = ParameterCount(record);
  const std::vector<double>& v = inner.values;
  std::vector<double> theta(static_cast<std::size_t>(BlockSize(record)), 0.0);
  if (record.offset) theta[static_cast<std::size_t>(p)] = inner.y0 - y0;
  if (record.input_offset) theta[static_cast<std::size_t>(InputOffsetIndex(record))] = inner.u0 - u0;
  const auto log_lag = [&](double tau) {
    return std::clamp(std::log(tau), std::log(record.dt_s / kTimeConstantRange),
                      std::log(record.length_s * kTimeConstantRange));
  };
  const auto delay = [&](double td) { return std::clamp(td, 0.0, record.max_delay_s); };
  theta[0] = v[0];
  std::vector<std::vector<double>> starts;
  switch (record.kind) {
    case ProcessModelKind::kP2D:  // from Kp, Tp1, Td
      theta[1] = log_lag(v[1]);
      theta[2] = log_lag(record.dt_s / kTimeConstantRange);
      theta[3] = delay(v[2]);
      starts.push_back(theta);
      theta[2] = log_lag(record.dt_s / 2.0);
      theta[3] = delay(v[2] - record.dt_s / 2.0);
      starts.push_back(theta);
      break;
    case ProcessModelKind::kP2DU: {  // from Kp, Tp1, Tp2, Td
      const double tw = std::sqrt(v[1] * v[2]), zeta = (v[1] + v[2]) / (2.0 * tw);
      theta[1] = log_lag(tw);
      theta[2] = std::clamp(zeta, kMinZeta, kMaxZeta);
      theta[3] = delay(v[3]);
      starts.push_back(theta);
      // Lags too far apart for a pair: the critically damped pair of the
      // same sum of time constants (2 Zeta Tw = Tp1 + Tp2) too.
      if (zeta > kMaxZeta) {
        theta[1] = log_lag(0.5 * (v[1] + v[2]));
        theta[2] = kMaxZeta;
        starts.push_back(theta);
      }
      break;
    }
    case ProcessModelKind::kP2DZ:  // from Kp, Tp1, Tp2, Td; Tz = 0
      theta[1] = log_lag(v[1]);
      theta[2] = log_lag(v[2]);
      theta[3] = 0.0;
      theta[4] = delay(v[3]);
      starts.push_back(theta);
      break;
    default:
      break;
  }
  return starts;
}

// Which parameters sit at (within 1e-6, relative to the bound's scale, of)
// a bound of the fit: "lower", "upper" or "" for each. Td at 0, Zeta at 1 (or
// at its floor), a time constant at dt/1000 or 1000 times the record.
std::vector<std::string> AtBound(const Record& record, const std::vector<double>& values) {
  std::vector<std::string> at(values.size());
  const int p = static_cast<int>(values.size());
  if (p == 0) return at;
  const double td = values.back();
  if (td <= 1e-6 * record.dt_s)
    at.back() = "lower";
  else if (td >= record.max_delay_s * (1 - 1e-6))
    at.back() = "upper";
  for (int i = 1; i < p - 1 && record.kind != ProcessModelKind::kTf; ++i) {
    const double v = values[static_cast<std::size_t>(i)];
    std::string& a = at[static_cast<std::size_t>(i)];
    if (IsLogParameter(record, i)) {
      if (v <= record.dt_s / kTimeConstantRange * (1 + 1e-6))
        a = "lower";
      else if (v >= record.length_s * kTimeConstantRange * (1 - 1e-6))
        a = "upper";
    } else if (!IsZeroParameter(record.kind, i)) {  // Zeta
      if (v >= 1.0 - 1e-6)
        a = "upper";
      else if (v <= kMinZeta * (1 + 1e-6))
        a = "lower";
    }
  }
  return at;
}

// The plain warnings of IdentifyResult::warnings.
std::vector<std::string> Warnings(const Record& record, const IdentifyResult& r) {
  const double dt_s = record.dt_s, length_s = record.length_s, max_delay_s = record.max_delay_s;
  std::vector<std::string> w;
  if (!r.covariance_ok) w.push_back("no intervals: " + r.covariance_message);
  for (std::size_t i = 0; i < r.names.size() && r.covariance_ok; ++i) {
    const double half = 1.96 * r.standard_errors[i];
    if (!r.at_bound[i].empty()) continue;  // said below, with its one-sided interval
    if (half > std::abs(r.values[i]))
      w.push_back(r.names[i] + " = " + Number(r.values[i]) + " +- " + Number(half) +
                  " (95 %): the interval is wider than the value, so the data do not determine " +
                  r.names[i]);
  }
  const double td = r.model.td_s;
  if (r.at_bound.back() == "lower")
    w.push_back(
        "Td = " + Number(td) +
        " s is at its lower bound 0: the record shows no dead time the fit can resolve; its interval is "
        "one-sided and not reported");
  for (std::size_t i = 0; i < r.names.size(); ++i)
    if (r.names[i] == "Zeta" && !r.at_bound[i].empty())
      w.push_back("Zeta = " + Number(r.values[i]) + " is at its " + r.at_bound[i] + " bound (" +
                  (r.at_bound[i] == "upper" ? "1: the poles are real or nearly so, which p2d describes"
                                            : Number(kMinZeta) + ": an undamped oscillation") +
                  "); its interval is one-sided and not reported");
  if (r.starts >= 3 && r.starts_at_best < 3)
    w.push_back("only " + std::to_string(r.starts_at_best) + " of " + std::to_string(r.starts) +
                " starts reached the best cost" +
                (r.bounds_refit_improved ? " (the refit with the parameters at a bound held there found it)"
                 : r.delay_profile_improved ? " (the delay's profile found it)"
                                            : "") +
                ": the optimum may not be the global one; try more --starts or another --seed");
  if (td >= max_delay_s * (1 - 1e-6))
    w.push_back("Td = " + Number(td) + " s is at its bound (" + Number(max_delay_s) +
                " s, half the record): the delay may be longer than the record can show");
  for (std::size_t i = 0; i < r.names.size(); ++i) {
    if (!IsLogParameter(record, static_cast<int>(i))) continue;
    const double t = r.values[i];
    if (t <= dt_s / kTimeConstantRange * (1 + 1e-6) || t >= length_s * kTimeConstantRange * (1 - 1e-6))
      w.push_back(r.names[i] + " = " + Number(t) + " s is at its bound [" +
                  Number(dt_s / kTimeConstantRange) + ", " + Number(length_s * kTimeConstantRange) +
                  "] s: the model's order may be wrong; its interval is one-sided and not reported");
  }
  // An exact fit (residual RMS below 1e-9 of the output's spread, as with
  // noise-free data) leaves rounding in its residuals: not worth a warning.
  const bool exact = r.fit_percent > 100.0 * (1.0 - 1e-9);
  if (r.whiteness.lags > 0 && !r.whiteness.white && !exact)
    w.push_back("the residuals are not white (Ljung-Box Q = " + Number(r.whiteness.ljung_box_q) + " over " +
                std::to_string(r.whiteness.lags) + " lags, p = " + Number(r.whiteness.p_value) +
                "): the model leaves dynamics unexplained, or the noise is coloured");
  return w;
}

// Figures of merit of the fit at `theta` into *result.
void Summarise(const Record& record, const IdentifyData& data, const std::vector<double>& theta, double cost,
               IdentifyResult* result) {
  const double n = static_cast<double>(data.y.size());
  result->model = ModelOf(record, theta.data());
  result->names = ParameterNames(record.kind, record.poles, record.zeros);
  result->values = ParameterValues(result->model);
  result->cost = cost;
  double mean = 0.0;
  for (double v : data.y) mean += v / n;
  double spread = 0.0;
  for (double v : data.y) spread += (v - mean) * (v - mean);
  result->fit_percent = 100.0 * (1.0 - std::sqrt(2.0 * cost) / std::sqrt(spread));
  result->aic =
      n * std::log(2.0 * cost / n) + 2.0 * (BlockSize(record) + FittedStates(record, result->model));
  const double offset = OffsetOf(record, theta.data());
  result->y0 += offset;
  result->y0_estimated = record.offset;
  result->u0 += InputOffsetOf(record, theta.data());
  result->u0_estimated = record.input_offset;
  result->covariance_ok =
      Covariance(record, theta, cost, &result->standard_errors, &result->covariance,
                 &result->y0_standard_error, &result->u0_standard_error, &result->covariance_message);
  std::vector<double> yhat;
  result->initial_state.assign(static_cast<std::size_t>(internal::ModelOrder(result->model)), 0.0);
  if (TrySimulate(result->model, record, &yhat, offset, InputOffsetOf(record, theta.data()), true,
                  &result->initial_state)) {
    if (result->initial_state.empty())
      result->initial_state.assign(static_cast<std::size_t>(internal::ModelOrder(result->model)), 0.0);
    for (std::size_t k = 0; k < yhat.size(); ++k) {
      result->simulated.push_back(result->y0 + yhat[k]);
      result->residuals.push_back(record.dy[k] - offset - yhat[k]);
    }
    result->whiteness = ResidualWhiteness(result->residuals);
    // The cost of the parameters reported, from the residuals reported.
    double resimulated = 0.0;
    for (double r : result->residuals) resimulated += 0.5 * r * r;
    result->cost = resimulated;
  }
  result->at_bound = AtBound(record, result->values);
  for (std::size_t i = 0; i < result->at_bound.size(); ++i)
    if (!result->at_bound[i].empty() && i < result->standard_errors.size()) result->standard_errors[i] = kNaN;
  result->warnings = Warnings(record, *result);
}

}  // namespace

Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                IdentifyResult* result) {
  ProcessModelKind inner_kind;
  if (const Status shape = internal::CheckTfShape(kind, options.poles, options.zeros); !shape.ok())
    return shape;
  if (!options.nested_starts || !ContainedKind(kind, &inner_kind))
    return Identify(data, kind, options, nullptr, result);
  // The contained model's fit is a start only: a quarter of the starts (its
  // optimum, of fewer parameters, is reached from fewer), the ARX start and
  // the delay's profile as asked.
  // Its own contained model is not fitted: one level of nesting.
  IdentifyOptions inner_options = options;
  inner_options.starts = std::max(1, (options.starts + 3) / 4);
  inner_options.nested_starts = false;
  IdentifyResult inner;
  const Status status = Identify(data, inner_kind, inner_options, &inner);
  if (status.code() == StatusCode::kInvalidInput) return status;
  return Identify(data, kind, options, status.ok() ? &inner : nullptr, result);
}

Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                const IdentifyResult* contained, IdentifyResult* result) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  Record record;
  record.kind = kind;
  const Status shape = internal::CheckTfShape(kind, options.poles, options.zeros);
  if (!shape.ok()) return shape;
  record.poles = options.poles;
  record.zeros = options.zeros;
  Sampling sampling;
  const Status status = CheckData(data, &sampling);
  if (!status.ok()) return status;
  record.dt_s = sampling.mean_interval_s;
  record.t = data.t;
  record.hold = options.intersample;
  record.initial = options.initial_condition;
  record.piecewise =
      !sampling.uniform || record.hold == Intersample::kFoh || record.initial != InitialCondition::kZero;
  *result = IdentifyResult{};
  result->sampling = sampling;
  result->intersample = options.intersample;
  result->initial_condition = options.initial_condition;
  result->u0 = std::isnan(options.u0) ? data.u[0] : options.u0;
  // Not given: estimated, from the first sample as its start.
  result->y0 = std::isnan(options.y0) ? data.y[0] : options.y0;
  record.offset = std::isnan(options.y0);
  record.input_offset = options.estimate_u0;
  for (std::size_t k = 0; k < data.u.size(); ++k) {
    record.du.push_back(data.u[k] - result->u0);
    record.dy.push_back(data.y[k] - result->y0);
  }
  // A constant input is a step from u0 when u0 is given; at its default,
  // the first sample, there is no input to respond to.
  if (std::all_of(data.u.begin(), data.u.end(), [&](double v) { return v == data.u[0]; }) &&
      std::isnan(options.u0))
    return Status::InvalidInput("constant input: u is " + Number(data.u[0]) +
                                " throughout and u0 is its first sample, so nothing can be identified; a "
                                "step test that starts at the "
                                "step needs the input before it: give --u0 (e.g. --u0 0)");
  if (record.initial == InitialCondition::kSteadyState && kind == ProcessModelKind::kP1DI &&
      record.du[0] != 0.0)
    return Status::InvalidInput(
        "initial condition steady-state: P1DI integrates, so it has no steady state at u[0] = " +
        Number(data.u[0]) + " unless u0 is that value too (u0 = " + Number(result->u0) + ")");
  if (Status s = CheckResponse(data); !s.ok()) return s;
  record.length_s = data.t.back() - data.t.front();
  record.max_delay_s = options.max_delay_fraction * record.length_s;
  const std::vector<std::vector<double>> nested =
      contained && options.nested_starts ? NestedStarts(record, *contained, result->u0, result->y0)
                                         : std::vector<std::vector<double>>{};
  result->nested_starts = static_cast<int>(nested.size());
  std::vector<double> theta = MultiStart(record, options, nested, &result->start_costs, &result->arx_start);
  if (theta.empty())
    return Status::RunnerFailed(
        "no start of the fit converged: " + std::to_string(options.starts) + " starts (seed " +
        std::to_string(options.seed) + ") of " + ToString(kind) + ", at most " +
        std::to_string(options.max_iterations) +
        " iterations each, all ended at a non-finite cost; check the record's units and outliers, or try "
        "more starts (--starts), another seed or another model");
  double best = *std::min_element(result->start_costs.begin(), result->start_costs.end());
  // Near Td = 0 only (within two samples): elsewhere the starts' spread
  // finds the delay (identify_study_test), and the profile's refits would
  // double the cost of a fit.
  const double best_td =
      kind == ProcessModelKind::kTf ? 0.0 : theta[static_cast<std::size_t>(ParameterCount(record) - 1)];
  if (kind != ProcessModelKind::kTf && options.delay_profile && best_td < 2.0 * record.dt_s)
    result->delay_profile_improved = ProfileDelay(record, options, &theta, &best);
  if (kind != ProcessModelKind::kTf && options.bounds_refit)
    result->bounds_refit_improved = RefitAtBounds(record, options, &theta, &best);
  // P2D's time constants are interchangeable: report Tp1 >= Tp2.
  if ((kind == ProcessModelKind::kP2D || kind == ProcessModelKind::kP2DZ) && theta[2] > theta[1])
    std::swap(theta[1], theta[2]);
  double scale = 0.0;
  for (double v : record.dy) scale += 0.5 * v * v;
  // Within 1e-8 of the best cost, relative; a record fitted exactly (best
  // cost ~ 0) is measured against 1e-16 of the cost of the zero model.
  const double tolerance = 1e-8 * std::max(best, 1e-16 * scale);
  for (double c : result->start_costs) result->starts_at_best += c - best <= tolerance ? 1 : 0;
  result->starts = static_cast<int>(result->start_costs.size());
  result->seed = options.seed;
  result->samples = static_cast<int>(data.y.size());
  result->dt_s = record.dt_s;
  Summarise(record, data, theta, best, result);
  return Status::Ok();
}

}  // namespace pidlab::identify
