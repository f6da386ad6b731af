// The fit of identify.h. The parameters Ceres sees, theta, are in the order
// of ParameterNames: Kp free, every time constant (Tp1, Tp2, Tw) as its
// logarithm (positive, and scaled alike whatever its size), Zeta bounded to
// (0, 1) and Td bounded to [0, max_delay_fraction of the record]. The delay
// stays continuous: DiscretePlant splits it over the sample exactly, so the
// cost is a continuous function of Td and central differences see it. A
// TF's coefficients are free (tf_start.h; docs/identify.md, "A general
// transfer function").

#include "pidlab/identify/identify.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "arx_start.h"
#include "fit_problem.h"
#include "pidlab/optim/sobol.h"
#include "tf_start.h"

namespace pidlab::identify {
namespace {

using internal::BlockSize;
using internal::ContainedKind;
using internal::FitAtDelay;
using internal::FitFrom;
using internal::FitHolding;
using internal::InputOffsetIndex;
using internal::InputOffsetOf;
using internal::IsLogParameter;
using internal::IsZeroParameter;
using internal::kMaxZeta;
using internal::kMinZeta;
using internal::kTimeConstantRange;
using internal::ModelOf;
using internal::NestedStarts;
using internal::Number;
using internal::OffsetOf;
using internal::ParameterCount;
using internal::Record;
using internal::SameKindStart;
using internal::SetGainByLeastSquares;
using internal::Summarise;
using internal::TrySimulate;

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
    cost += internal::SampleCost(record, record.dy[k] - offset - yhat[k]);
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

// AIC of a fit of `cost` on `record` (Summarise's, the initial state's
// entries of kEstimate left out: lower, so that pruning errs on the side of
// fitting).
double AicOf(const Record& record, double cost) {
  const double n = static_cast<double>(record.dy.size());
  return n * std::log(2.0 * cost / n) + 2.0 * BlockSize(record);
}

// The best of the starts: its theta, and every start's cost. The design's
// starts after the first quarter are skipped (counted in *skipped) while the
// best AIC is more than kPruneAic above aic_to_beat.
std::vector<double> MultiStart(const Record& record, const IdentifyOptions& options,
                               const std::vector<std::vector<double>>& nested, std::vector<double>* costs,
                               bool* arx_used, double aic_to_beat = std::numeric_limits<double>::infinity(),
                               int* skipped = nullptr) {
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
    const double free_cost = FitFrom(record, options, &freed, best_cost);
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
  const auto stop = [&] { return options.cancelled && options.cancelled(); };
  for (const std::vector<double>& theta : nested)
    if (!stop()) fit(theta, true);
  const int at_least = std::max(1, (options.starts + 3) / 4);
  for (int s = 0; s < options.starts && !stop(); ++s) {
    if (s >= at_least && AicOf(record, best_cost) > aic_to_beat + internal::kPruneAic) {
      if (skipped) *skipped = options.starts - s;
      break;
    }
    fit(StartPoint(record, sobol, s), false);
  }
  return stop() ? std::vector<double>{} : best;
}

// The loss of IdentifyOptions on the record; a robust one needs its scale
// here (Identify and IdentifyAuto derive it first).
Status SetLoss(const IdentifyOptions& options, Record* record, IdentifyResult* result) {
  result->loss = options.loss;
  if (options.loss == Loss::kL2) return Status::Ok();
  if (std::isnan(options.loss_scale))
    return Status::InvalidInput("loss " + ToString(options.loss) +
                                " needs its scale: give loss_scale, or call Identify, which derives it");
  record->loss = internal::MakeLoss(options.loss, options.loss_scale);
  result->loss_scale = options.loss_scale;
  result->loss_scale_source = "given";
  return Status::Ok();
}

// The record of one fit with its operating point taken off, checked; the
// result's settings (sampling, offsets, loss) into *result.
Status MakeRecord(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                  Record* record, IdentifyResult* result) {
  std::string error;
  if (!options.IsValid(&error)) return Status::InvalidInput(error);
  record->kind = kind;
  const Status shape = internal::CheckTfShape(kind, options.poles, options.zeros);
  if (!shape.ok()) return shape;
  record->poles = options.poles;
  record->zeros = options.zeros;
  if (data.y.size() > options.max_samples)
    return Status::InvalidInput("the record has " + std::to_string(data.y.size()) +
                                " samples, more than max_samples = " + std::to_string(options.max_samples) +
                                ": decimate it (DecimateRecord) or raise the limit");
  Sampling sampling;
  const Status status = CheckData(data, &sampling);
  if (!status.ok()) return status;
  record->dt_s = sampling.mean_interval_s;
  record->t = data.t;
  record->hold = options.intersample;
  record->initial = options.initial_condition;
  record->piecewise =
      !sampling.uniform || record->hold == Intersample::kFoh || record->initial != InitialCondition::kZero;
  *result = IdentifyResult{};
  result->sampling = sampling;
  result->intersample = options.intersample;
  result->initial_condition = options.initial_condition;
  result->u0 = std::isnan(options.u0) ? data.u[0] : options.u0;
  result->u0_source = options.estimate_u0      ? "estimated"
                      : std::isnan(options.u0) ? "the first sample of u"
                                               : "given";
  // Not given: estimated, from the first sample as its start.
  result->y0 = std::isnan(options.y0) ? data.y[0] : options.y0;
  record->offset = std::isnan(options.y0);
  record->input_offset = options.estimate_u0;
  for (std::size_t k = 0; k < data.u.size(); ++k) {
    record->du.push_back(data.u[k] - result->u0);
    record->dy.push_back(data.y[k] - result->y0);
  }
  // A constant input is a step from u0 when u0 is given; at its default,
  // the first sample, there is no input to respond to.
  if (std::all_of(data.u.begin(), data.u.end(), [&](double v) { return v == data.u[0]; }) &&
      std::isnan(options.u0))
    return Status::InvalidInput("constant input: u is " + Number(data.u[0]) +
                                " throughout and u0 is its first sample, so nothing can be identified; a "
                                "step test that starts at the "
                                "step needs the input before it: give --u0 (e.g. --u0 0)");
  if (record->initial == InitialCondition::kSteadyState && kind == ProcessModelKind::kP1DI &&
      record->du[0] != 0.0)
    return Status::InvalidInput(
        "initial condition steady-state: P1DI integrates, so it has no steady state at u[0] = " +
        Number(data.u[0]) + " unless u0 is that value too (u0 = " + Number(result->u0) + ")");
  if (Status s = CheckResponse(data); !s.ok()) return s;
  record->length_s = data.t.back() - data.t.front();
  record->max_delay_s = options.max_delay_fraction * record->length_s;
  return SetLoss(options, record, result);
}

// After the starts (*theta at *best): the delay's profile, the refit at the
// bounds, Tp1 >= Tp2, and how many starts reached the best cost.
void Refine(const Record& record, const IdentifyOptions& options, std::vector<double>* theta, double* best,
            IdentifyResult* result) {
  const ProcessModelKind kind = record.kind;
  // Near Td = 0 only (within two samples): elsewhere the starts' spread
  // finds the delay (identify_study_test), and the profile's refits would
  // double the cost of a fit.
  const double best_td =
      kind == ProcessModelKind::kTf ? 0.0 : (*theta)[static_cast<std::size_t>(ParameterCount(record) - 1)];
  if (kind != ProcessModelKind::kTf && options.delay_profile && best_td < 2.0 * record.dt_s)
    result->delay_profile_improved = ProfileDelay(record, options, theta, best);
  if (kind != ProcessModelKind::kTf && options.bounds_refit)
    result->bounds_refit_improved = RefitAtBounds(record, options, theta, best);
  // P2D's time constants are interchangeable: report Tp1 >= Tp2.
  if ((kind == ProcessModelKind::kP2D || kind == ProcessModelKind::kP2DZ) && (*theta)[2] > (*theta)[1])
    std::swap((*theta)[1], (*theta)[2]);
  double scale = 0.0;
  for (double v : record.dy) scale += internal::SampleCost(record, v);
  // Within 1e-8 of the best cost, relative; a record fitted exactly (best
  // cost ~ 0) is measured against 1e-16 of the cost of the zero model.
  const double tolerance = 1e-8 * std::max(*best, 1e-16 * scale);
  for (double c : result->start_costs) result->starts_at_best += c - *best <= tolerance ? 1 : 0;
  result->starts = static_cast<int>(result->start_costs.size());
}

// A model on a record longer than options.start_samples: the starts
// (FitKind's, with the seeds) on the record decimated to that many samples,
// their best refitted on the record itself and refined there. The starts'
// figures (start_costs, starts, starts_at_best, the ARX and nested starts)
// are the decimated record's (docs/identify.md, "Long records").
Status FitFromDecimatedStarts(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                              const internal::Seeds& seeds, IdentifyResult* result) {
  Record record;
  if (Status s = MakeRecord(data, kind, options, &record, result); !s.ok()) return s;
  IdentifyData coarse;
  Decimation decimation;
  if (Status s = DecimateRecord(data, options.start_samples, options.intersample, &coarse, &decimation);
      !s.ok())
    return s;
  IdentifyOptions coarse_options = options;
  coarse_options.start_samples = 0;
  coarse_options.u0 = result->u0;  // the record's: not the decimated record's first sample
  IdentifyResult screened;
  if (Status s = internal::FitKind(coarse, kind, coarse_options, seeds, &screened); !s.ok()) return s;
  // Refitted from the starts' best (and a robust fit's l2 optimum), then,
  // if that ends above the contained model's optimum, from it too: a bigger
  // model never ends worse than the one it contains, whatever basin the
  // decimated record preferred.
  std::vector<double> theta = SameKindStart(record, screened, result->u0, result->y0);
  std::vector<double> costs = {FitFrom(record, options, &theta)};
  std::vector<std::vector<double>> seeded;
  if (seeds.same_kind) seeded.push_back(SameKindStart(record, *seeds.same_kind, result->u0, result->y0));
  if (seeds.contained && options.nested_starts && !(costs[0] <= seeds.contained->cost))
    for (std::vector<double>& start : NestedStarts(record, *seeds.contained, result->u0, result->y0))
      seeded.push_back(std::move(start));
  seeded.erase(std::remove_if(seeded.begin(), seeded.end(), [](const auto& v) { return v.empty(); }),
               seeded.end());
  if (!seeded.empty()) {
    IdentifyOptions refit_options = options;
    refit_options.starts = 0;
    refit_options.arx_start = false;
    refit_options.progress = nullptr;  // the starts' progress was shown
    bool arx_used = false;
    std::vector<double> seeded_costs;
    std::vector<double> from_seeds = MultiStart(record, refit_options, seeded, &seeded_costs, &arx_used);
    if (!from_seeds.empty() && *std::min_element(seeded_costs.begin(), seeded_costs.end()) < costs[0])
      theta = from_seeds;
    costs.insert(costs.end(), seeded_costs.begin(), seeded_costs.end());
  }
  if (!std::isfinite(*std::min_element(costs.begin(), costs.end()))) theta.clear();
  if (options.cancelled && options.cancelled()) return Status::RunnerFailed("cancelled");
  if (theta.empty())
    return Status::RunnerFailed("the refit of " + std::string(ToString(kind)) + " on all " +
                                std::to_string(data.y.size()) + " samples, from the best of its starts on " +
                                std::to_string(coarse.y.size()) + ", ended at a non-finite cost");
  double best = *std::min_element(costs.begin(), costs.end());
  result->start_costs = costs;
  Refine(record, options, &theta, &best, result);
  result->start_costs = screened.start_costs;
  result->starts = screened.starts;
  result->starts_at_best = screened.starts_at_best;
  result->arx_start = screened.arx_start;
  result->nested_starts = screened.nested_starts;
  result->delay_profile_improved = result->delay_profile_improved || screened.delay_profile_improved;
  result->bounds_refit_improved = result->bounds_refit_improved || screened.bounds_refit_improved;
  result->seed = options.seed;
  result->samples = static_cast<int>(data.y.size());
  result->dt_s = record.dt_s;
  Summarise(record, data, theta, best, result, seeds.contained);
  return Status::Ok();
}

}  // namespace

namespace internal {

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

Status FitKind(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
               const Seeds& seeds, IdentifyResult* result) {
  if (options.start_samples > 0 && data.y.size() > options.start_samples)
    return FitFromDecimatedStarts(data, kind, options, seeds, result);
  Record record;
  if (Status s = MakeRecord(data, kind, options, &record, result); !s.ok()) return s;
  std::vector<std::vector<double>> nested;
  if (seeds.contained && options.nested_starts)
    nested = NestedStarts(record, *seeds.contained, result->u0, result->y0);
  if (seeds.same_kind) {
    std::vector<double> theta = SameKindStart(record, *seeds.same_kind, result->u0, result->y0);
    if (!theta.empty()) nested.push_back(theta);
  }
  result->nested_starts = static_cast<int>(nested.size());
  std::vector<double> theta = MultiStart(record, options, nested, &result->start_costs, &result->arx_start,
                                         seeds.aic_to_beat, &result->starts_skipped);
  if (options.cancelled && options.cancelled()) return Status::RunnerFailed("cancelled");
  if (theta.empty())
    return Status::RunnerFailed(
        "no start of the fit converged: " + std::to_string(options.starts) + " starts (seed " +
        std::to_string(options.seed) + ") of " + ToString(kind) + ", at most " +
        std::to_string(options.max_iterations) +
        " iterations each, all ended at a non-finite cost; check the record's units and outliers, or try "
        "more starts (--starts), another seed or another model");
  double best = *std::min_element(result->start_costs.begin(), result->start_costs.end());
  Refine(record, options, &theta, &best, result);
  result->seed = options.seed;
  result->samples = static_cast<int>(data.y.size());
  result->dt_s = record.dt_s;
  Summarise(record, data, theta, best, result, seeds.contained);
  return Status::Ok();
}

Status FitNested(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                 const IdentifyResult* same_kind, IdentifyResult* result) {
  ProcessModelKind inner_kind;
  if (!options.nested_starts || !ContainedKind(kind, &inner_kind))
    return FitKind(data, kind, options, Seeds{nullptr, same_kind}, result);
  // The contained model's fit is a start only: a quarter of the starts (its
  // optimum, of fewer parameters, is reached from fewer), the ARX start and
  // the delay's profile as asked.
  // Its own contained model is not fitted: one level of nesting.
  IdentifyOptions inner_options = options;
  inner_options.starts = std::max(1, (options.starts + 3) / 4);
  inner_options.nested_starts = false;
  IdentifyResult inner;
  const Status status = FitKind(data, inner_kind, inner_options, Seeds{}, &inner);
  if (status.code() == StatusCode::kInvalidInput) return status;
  return FitKind(data, kind, options, Seeds{status.ok() ? &inner : nullptr, same_kind}, result);
}

}  // namespace internal

Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                const IdentifyResult* contained, IdentifyResult* result) {
  return internal::FitKind(data, kind, options, internal::Seeds{contained, nullptr}, result);
}

}  // namespace pidlab::identify
