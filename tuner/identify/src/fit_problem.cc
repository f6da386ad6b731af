// The output-error problem of fit_problem.h: the model's response, the
// residuals Ceres sees and one fit from a start.

#include "fit_problem.h"

#include <glog/logging.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "pidlab/plant_sim/discrete_plant.h"
#include "piecewise_response.h"
#include "tf_start.h"

namespace pidlab::identify {
namespace internal {

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

namespace {

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

}  // namespace

// yhat of the model, false if it is not a valid plant or diverges (or, for
// a TF, not admissible: tf_start.h). `offset`, `project`, `state`: Simulate's.
bool TrySimulate(const ProcessModel& model, const Record& record, std::vector<double>* yhat, double offset,
                 double input_shift, bool project, std::vector<double>* state) {
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

// The residuals r_k = dy_k - offset - yhat_k, or under a robust loss
// sign(r_k) sqrt(rho(r_k^2)), so that Ceres's 1/2 sum of squares is 1/2 sum
// rho(r_k^2). The loss acts on each sample: the one residual block holds
// every sample (one simulation gives them all), and a loss given to Ceres
// with the block would act on the block's whole squared norm instead.
struct OutputError {
  const Record* record;
  bool operator()(double const* const* parameters, double* residuals) const {
    std::vector<double> yhat;
    const double offset = OffsetOf(*record, parameters[0]);
    if (!TrySimulate(ModelOf(*record, parameters[0]), *record, &yhat, offset,
                     InputOffsetOf(*record, parameters[0])))
      return false;
    for (std::size_t k = 0; k < yhat.size(); ++k) residuals[k] = record->dy[k] - offset - yhat[k];
    if (record->loss)
      for (std::size_t k = 0; k < yhat.size(); ++k)
        residuals[k] = std::copysign(std::sqrt(2.0 * SampleCost(*record, residuals[k])), residuals[k]);
    return true;
  }
};

// OutputError's residuals and Jacobian with the simulations shared: the
// model is linear in Kp and in the output offset (r = dy - offset - Kp g,
// g the response at Kp = 1), so one simulation gives the residuals and both
// their columns, and central differences (Ceres's step, 1e-6 relative) run
// two simulations per other parameter, not per parameter: 7 simulations an
// iteration for P2D instead of 11. Least squares on a uniform record (a
// robust loss, a piecewise response or a TF keep OutputError).
class SharedOutputError : public ceres::CostFunction {
 public:
  explicit SharedOutputError(const Record* record) : record_(record) {
    set_num_residuals(static_cast<int>(record->dy.size()));
    mutable_parameter_block_sizes()->push_back(BlockSize(*record));
  }
  static bool Applies(const Record& record) {
    return record.kind != ProcessModelKind::kTf && !record.piecewise && !record.loss;
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Record& r = *record_;
    const int q = BlockSize(r);
    std::vector<double> theta(parameters[0], parameters[0] + q);
    const double kp = theta[0], offset = OffsetOf(r, parameters[0]);
    theta[0] = 1.0;
    std::vector<double> g, plus, minus;
    if (!Unit(theta, &g)) return false;
    const std::size_t n = g.size();
    for (std::size_t k = 0; k < n; ++k) residuals[k] = r.dy[k] - offset - kp * g[k];
    if (!jacobians || !jacobians[0]) return true;
    double* jacobian = jacobians[0];
    const auto at = [&](std::size_t k, int i) -> double& {
      return jacobian[k * static_cast<std::size_t>(q) + static_cast<std::size_t>(i)];
    };
    for (int i = 0; i < q; ++i) {
      if (i == 0 || (r.offset && i == ParameterCount(r))) {
        for (std::size_t k = 0; k < n; ++k) at(k, i) = i == 0 ? -g[k] : -1.0;
        continue;
      }
      const double x = theta[static_cast<std::size_t>(i)];
      const double h = x == 0.0 ? 1e-6 : 1e-6 * std::abs(x);
      theta[static_cast<std::size_t>(i)] = x + h;
      const bool up = Unit(theta, &plus);
      theta[static_cast<std::size_t>(i)] = x - h;
      const bool down = Unit(theta, &minus);
      theta[static_cast<std::size_t>(i)] = x;
      if (!up || !down) return false;
      for (std::size_t k = 0; k < n; ++k) at(k, i) = -kp * (plus[k] - minus[k]) / (2.0 * h);
    }
    return true;
  }

 private:
  bool Unit(const std::vector<double>& theta, std::vector<double>* g) const {
    return TrySimulate(ModelOf(*record_, theta.data()), *record_, g, 0.0,
                       InputOffsetOf(*record_, theta.data()));
  }
  const Record* record_;
};

// The problem over one parameter block `theta`, with its bounds.
void BuildProblem(const Record& record, double* theta, ceres::Problem* problem) {
  const int p = ParameterCount(record);
  if (SharedOutputError::Applies(record)) {
    problem->AddResidualBlock(new SharedOutputError(&record), nullptr, theta);
  } else {
    auto* cost =
        new ceres::DynamicNumericDiffCostFunction<OutputError, ceres::CENTRAL>(new OutputError{&record});
    cost->AddParameterBlock(BlockSize(record));
    cost->SetNumResiduals(static_cast<int>(record.dy.size()));
    problem->AddResidualBlock(cost, nullptr, theta);
  }
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

namespace {

// Ends a solve at its next iteration once the options' cancelled() says so.
class CancelCallback : public ceres::IterationCallback {
 public:
  explicit CancelCallback(const IdentifyOptions& options) : options_(options) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return options_.cancelled && options_.cancelled() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const IdentifyOptions& options_;
};

// Ends a start once it has reached the best cost of the starts before it
// (within kReachedBest, relative) and stalls there (a step lowering the
// cost by under kStalled of it): it is converging on that optimum, or on one
// as low, and the rest of its way (a time constant walking to its bound,
// the last digits) changes nothing the fit reports but its own cost.
class ReachedBestCallback : public ceres::IterationCallback {
 public:
  static constexpr double kReachedBest = 1e-9, kStalled = 1e-10;
  explicit ReachedBestCallback(double best_cost) : best_cost_(best_cost) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    const bool reached = s.cost <= best_cost_ * (1.0 + kReachedBest);
    const bool stalled = s.step_is_successful && s.cost_change >= 0.0 && s.cost_change <= kStalled * s.cost;
    return reached && stalled && s.iteration > 0 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                 : ceres::SOLVER_CONTINUE;
  }

 private:
  double best_cost_;
};

}  // namespace

namespace {

// Ceres on `problem` with the tolerances given, one thread, silent, cancelled
// by the options, ended early by `reached` (or null); the final cost, or
// infinity if Ceres failed. A TF's start may walk to the edge of stability,
// where a central difference fails and Ceres stops with FAILURE, logged
// through glog as an error; the start's cost (infinite) says it, so glog is
// kept quiet.
double Solve(ceres::Problem* problem, const IdentifyOptions& options, double function_tolerance,
             double parameter_tolerance, ceres::IterationCallback* reached) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = function_tolerance;
  solver.gradient_tolerance = 1e-20;
  solver.parameter_tolerance = parameter_tolerance;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  CancelCallback cancel(options);
  solver.callbacks.push_back(&cancel);
  if (reached) solver.callbacks.push_back(reached);
  ceres::Solver::Summary summary;
  const int log_level = FLAGS_minloglevel;
  FLAGS_minloglevel = google::GLOG_FATAL;
  ceres::Solve(solver, problem, &summary);
  FLAGS_minloglevel = log_level;
  if (summary.termination_type == ceres::FAILURE || summary.termination_type == ceres::USER_FAILURE ||
      !std::isfinite(summary.final_cost))
    return std::numeric_limits<double>::infinity();
  return summary.final_cost;
}

}  // namespace

// One start's fit; the final cost, or infinity if Ceres failed.
double FitFrom(const Record& record, const IdentifyOptions& options, std::vector<double>* theta,
               double best_cost) {
  ceres::Problem problem;
  BuildProblem(record, theta->data(), &problem);
  ReachedBestCallback reached(best_cost);
  return Solve(&problem, options, 1e-15, 1e-13, std::isfinite(best_cost) ? &reached : nullptr);
}

// The parameters `held` (indices into theta) held where *theta has them,
// the others refitted from *theta; the cost, or infinity if Ceres failed.
double FitHolding(const Record& record, const IdentifyOptions& options, const std::vector<int>& held,
                  std::vector<double>* theta) {
  ceres::Problem problem;
  BuildProblem(record, theta->data(), &problem);
  problem.SetManifold(theta->data(), new ceres::SubsetManifold(BlockSize(record), held));
  return Solve(&problem, options, 1e-12, 1e-10, nullptr);
}

// Td held at `td`, the other parameters refitted from *theta.
double FitAtDelay(const Record& record, const IdentifyOptions& options, double td,
                  std::vector<double>* theta) {
  const int p = ParameterCount(record);
  (*theta)[static_cast<std::size_t>(p - 1)] = td;
  return FitHolding(record, options, {p - 1}, theta);
}

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::shared_ptr<const ceres::LossFunction> MakeLoss(Loss loss, double scale) {
  switch (loss) {
    case Loss::kHuber:
      return std::make_shared<const ceres::HuberLoss>(scale);
    case Loss::kCauchy:
      return std::make_shared<const ceres::CauchyLoss>(scale);
    case Loss::kL2:
      break;
  }
  return nullptr;
}

double SampleCost(const Record& record, double r) {
  if (!record.loss) return 0.5 * r * r;
  double rho[3];
  record.loss->Evaluate(r * r, rho);
  return 0.5 * rho[0];
}

double SampleWeight(const Record& record, double r) {
  if (!record.loss) return 1.0;
  double rho[3];
  record.loss->Evaluate(r * r, rho);
  return rho[1];
}

}  // namespace internal

namespace {

// DiscretePlant's response to u - u0 from rest (Output, then Step, at every
// sample) with the same sums in the same order, so the same bits, but its
// state of N entries in an array and its delay line an offset into the
// input: the simulation every residual of every fit runs, several times per
// iteration, at a few times DiscretePlant's speed.
template <int N>
void Response(const DiscretePlant& plant, const std::vector<double>& v, std::vector<double>* yhat) {
  double phi[N][N], g1[N], g0[N], c[N], x[N], next[N];
  const bool split = plant.gamma0().size() != 0;
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) phi[i][j] = plant.phi()(i, j);
    g1[i] = plant.gamma1()(i);
    g0[i] = split ? plant.gamma0()(i) : 0.0;
    c[i] = plant.c()(i);
    x[i] = 0.0;
  }
  const long d = plant.delay_steps();
  const long n = static_cast<long>(v.size());
  for (long k = 0; k < n; ++k) {
    double y = 0.0;
    for (int i = 0; i < N; ++i) y += c[i] * x[i];
    (*yhat)[static_cast<std::size_t>(k)] = y;
    // InputDelayLine::Push: u_(k-d) and u_(k-d+1), zero before the record.
    const double now = v[static_cast<std::size_t>(k)];
    const double oldest = d == 0 ? now : k >= d ? v[static_cast<std::size_t>(k - d)] : 0.0;
    const double next_oldest = d <= 1 ? now : k + 1 >= d ? v[static_cast<std::size_t>(k + 1 - d)] : 0.0;
    for (int i = 0; i < N; ++i) {
      double acc = 0.0;
      for (int j = 0; j < N; ++j) acc += phi[i][j] * x[j];
      next[i] = split ? (acc + g1[i] * oldest) + g0[i] * next_oldest : acc + g1[i] * oldest;
    }
    for (int i = 0; i < N; ++i) x[i] = next[i];
  }
}

}  // namespace

std::vector<double> SimulateModel(const ProcessModel& model, const std::vector<double>& u, double u0,
                                  double dt_s) {
  DiscretePlant plant(model.ToTransferFunction(), dt_s, model.delay_s());
  std::vector<double> yhat(u.size());
  std::vector<double> v(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) v[k] = u[k] - u0;
  switch (plant.order()) {
    case 1:
      Response<1>(plant, v, &yhat);
      return yhat;
    case 2:
      Response<2>(plant, v, &yhat);
      return yhat;
    case 3:
      Response<3>(plant, v, &yhat);
      return yhat;
    default:
      break;
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    yhat[k] = plant.Output();
    plant.Step(v[k]);
  }
  return yhat;
}

}  // namespace pidlab::identify
