#pragma once
// The output-error problem every fit of identify.cc solves, shared by its
// steps (the starts, the refinements, the summary): identify.cc, internal.
// The parameters Ceres sees, theta, are in the order of ParameterNames: Kp
// free, every time constant (Tp1, Tp2, Tw) as its logarithm (positive, and
// scaled alike whatever its size), Zeta bounded to (0, 1) and Td bounded to
// [0, max_delay_fraction of the record], then the offsets if estimated.

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "pidlab/identify/identify.h"
#include "pidlab/identify/process_model.h"
#include "piecewise_response.h"

namespace pidlab::identify::internal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Bounds of Zeta inside (0, 1).
inline constexpr double kMinZeta = 1e-3;
inline constexpr double kMaxZeta = 1.0 - 1e-9;
// How far the time constants may go from the record's scales: [dt / 1000, 1000 T_record].
inline constexpr double kTimeConstantRange = 1e3;

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
  /// The robust loss on each residual (Ceres's HuberLoss or CauchyLoss);
  /// nullptr: least squares.
  std::shared_ptr<const ceres::LossFunction> loss;
};

/// Ceres's loss object for `loss` of scale a; nullptr for Loss::kL2.
std::shared_ptr<const ceres::LossFunction> MakeLoss(Loss loss, double scale);
/// 1/2 rho(r^2), the cost of one residual under the record's loss.
double SampleCost(const Record& record, double r);
/// rho'(r^2), the weight the loss gives the sample (1 for least squares).
double SampleWeight(const Record& record, double r);

inline int ParameterCount(const Record& record) {
  return static_cast<int>(ParameterNames(record.kind, record.poles, record.zeros).size());
}
// Ceres's parameter block: the model's parameters, then the offset if estimated.
inline int BlockSize(const Record& record) {
  return ParameterCount(record) + (record.offset ? 1 : 0) + (record.input_offset ? 1 : 0);
}
inline int InputOffsetIndex(const Record& record) { return ParameterCount(record) + (record.offset ? 1 : 0); }
inline double InputOffsetOf(const Record& record, const double* theta) {
  return record.input_offset ? theta[InputOffsetIndex(record)] : 0.0;
}
inline double OffsetOf(const Record& record, const double* theta) {
  return record.offset ? theta[ParameterCount(record)] : 0.0;
}

// The initial state's entries fitted by projection (kEstimate): parameters
// too, for the degrees of freedom and the AIC.
inline int FittedStates(const Record& record, const ProcessModel& model) {
  return record.initial == InitialCondition::kEstimate ? internal::ModelOrder(model) : 0;
}

// theta[i] is the logarithm of a time constant.
inline bool IsLogParameter(const Record& record, int i) {
  const int p = ParameterCount(record);
  const ProcessModelKind kind = record.kind;
  return kind != ProcessModelKind::kTf && i > 0 && i < p - 1 &&
         !(kind == ProcessModelKind::kP2DU && i == 2) && !(kind == ProcessModelKind::kP2DZ && i == 3);
}

// theta[i] is P2DZ's Tz (any sign).
inline bool IsZeroParameter(ProcessModelKind kind, int i) {
  return kind == ProcessModelKind::kP2DZ && i == 3;
}

/// The model of the parameter block theta.
ProcessModel ModelOf(const Record& record, const double* theta);

/// yhat of the model, false if it is not a valid plant or diverges (or, for
/// a TF, not admissible: tf_start.h). With kEstimate and `project`, the free
/// response that best fits dy - offset added (its state in *state).
bool TrySimulate(const ProcessModel& model, const Record& record, std::vector<double>* yhat,
                 double offset = 0.0, double input_shift = 0.0, bool project = true,
                 std::vector<double>* state = nullptr);

/// The problem over one parameter block `theta`, with its bounds.
void BuildProblem(const Record& record, double* theta, ceres::Problem* problem);

/// Kp by linear least squares at the other parameters of *theta (a TF's
/// numerator likewise); left at 1 if the model cannot be simulated.
void SetGainByLeastSquares(const Record& record, std::vector<double>* theta);

/// One start's fit from *theta; the final cost, or infinity if Ceres failed.
/// best_cost finite (the best of the starts before it): the fit ends once it
/// has reached that cost within 1e-9 relative and stalls there.
double FitFrom(const Record& record, const IdentifyOptions& options, std::vector<double>* theta,
               double best_cost = std::numeric_limits<double>::infinity());
/// The parameters `held` held where *theta has them, the others refitted.
double FitHolding(const Record& record, const IdentifyOptions& options, const std::vector<int>& held,
                  std::vector<double>* theta);
/// Td held at `td`, the other parameters refitted from *theta.
double FitAtDelay(const Record& record, const IdentifyOptions& options, double td,
                  std::vector<double>* theta);

std::string Number(double v);

/// Starts from other fits' optima: the model `kind` contains (P1D for P2D,
/// ...) and the same kind fitted with another loss (the l2 fit before a
/// robust one). nullptr: none.
struct Seeds {
  const IdentifyResult* contained = nullptr;
  const IdentifyResult* same_kind = nullptr;
  /// IdentifyAuto's lowest AIC of the kinds fitted before (infinity: none):
  /// once a quarter of the design's starts are done, the rest are skipped
  /// while the best AIC is more than kPruneAic above it.
  double aic_to_beat = std::numeric_limits<double>::infinity();
};
/// How far above auto's lowest AIC a kind's best start may be before its
/// remaining design starts are skipped: more than 10 is a kind the data rule
/// out (Burnham and Anderson), and those starts would have to find an
/// optimum below all that the seeded starts and a quarter of the design saw.
inline constexpr double kPruneAic = 10.0;

/// Starts at the optimum `inner` of the model `record`'s kind contains
/// (nested_starts.cc), in Ceres's coordinates, the offsets relative to the
/// record's u0 and y0; and the optimum of the same kind fitted with another
/// loss (empty if `prior` is of another kind).
std::vector<std::vector<double>> NestedStarts(const Record& record, const IdentifyResult& inner, double u0,
                                              double y0);
std::vector<double> SameKindStart(const Record& record, const IdentifyResult& prior, double u0, double y0);

/// The parameters `r` (summarised on `record`) does not identify
/// (IdentifyResult::not_identifiable; identifiability.cc), and the warning
/// that says one, against the contained model's fit when given.
std::vector<IdentifyResult::NotIdentifiable> NotIdentifiable(const Record& record, const IdentifyResult& r);
std::string NotIdentifiableWarning(const IdentifyResult::NotIdentifiable& n, const IdentifyResult& r,
                                   const IdentifyResult* contained);
/// One fit of `kind` (identify.cc): u0 as the options give it (NaN: the
/// first sample), from the design's starts, the ARX start and the seeds.
Status FitKind(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
               const Seeds& seeds, IdentifyResult* result);
/// FitKind with the contained model fitted first when options.nested_starts
/// (a quarter of the starts, no nesting of its own).
Status FitNested(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                 const IdentifyResult* same_kind, IdentifyResult* result);
/// The model `kind` contains, whose optimum starts `kind`'s fit: P1D in P2D,
/// P2D in P2DU and P2DZ.
bool ContainedKind(ProcessModelKind kind, ProcessModelKind* inner);

/// Whether Identify fits both rests (rest_and_loss.cc): u0 neither given nor
/// estimated, the initial condition kZero, u varying from u[0] != 0.
bool RestsToChoose(const IdentifyData& data, const IdentifyOptions& options);
/// The fit at rest under u[0] (`first`) or the one at rest at u = 0
/// (`zero`), whichever has the lower AIC, moved into *result with
/// rest_hypotheses and u0_source; the first's status if neither fitted.
Status ChooseRest(double u_first, const Status& first_status, IdentifyResult* first,
                  const Status& zero_status, IdentifyResult* zero, IdentifyResult* result);
/// A robust loss's scale a from the l2 fit's residuals (kHuberScaleInSigmas
/// or kCauchyScaleInSigmas robust standard deviations), and in *source how.
double DerivedLossScale(Loss loss, const std::vector<double>& residuals, const std::vector<double>& y,
                        std::string* source);

/// The figures of merit of the fit at `theta` (cost: its cost) into *result:
/// the model, the covariance, the residuals, the bounds, the warnings
/// (fit_summary.cc).
void Summarise(const Record& record, const IdentifyData& data, const std::vector<double>& theta, double cost,
               IdentifyResult* result, const IdentifyResult* contained = nullptr);

}  // namespace pidlab::identify::internal
