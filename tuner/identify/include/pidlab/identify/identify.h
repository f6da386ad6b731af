#pragma once
// A process model (process_model.h) fitted to one record of sampled input
// and output by least squares on the output error: the residuals are
// y_k - y0 - yhat_k, with yhat the exact zero-order-hold (or first-order-hold) response of the
// model, its delay included and fractional (DiscretePlant(tf, dt, Td), or on
// a non-uniform grid the same response interval by interval), to u - u0
// from a zero state (or a steady or estimated one: InitialCondition). Ceres fits from several starts and
// keeps the best. docs/identify.md, "Identifying a model from a CSV".

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pidlab/identify/process_model.h"
#include "pidlab/spec/status.h"

namespace pidlab::identify {

/// One record: sample times t (s, strictly increasing, uniform or not), input
/// u and output y. u_k is held from t_k to t_(k+1).
struct IdentifyData {
  std::vector<double> t;
  std::vector<double> u;
  std::vector<double> y;
};

/// How a record is sampled (CheckData). Uniform: every interval within
/// kUniformSamplingTolerance of the mean, relative; the fit then runs
/// DiscretePlant over the mean interval. Otherwise it simulates the exact
/// response interval by interval (docs/identify.md, "Non-uniform sampling").
struct Sampling {
  bool uniform = true;
  double mean_interval_s = 0.0;  // (t_(N-1) - t_0) / (N - 1)
  double min_interval_s = 0.0;
  double max_interval_s = 0.0;
};

/// The fewest samples a record may have.
inline constexpr std::size_t kMinSamples = 20;
/// The largest magnitude of a t, u or y sample (the limit of every number
/// pidlab takes), the shortest interval of t, and how far beyond its column's
/// median absolute deviation a sample may lie (CheckData).
inline constexpr double kMaxRecordMagnitude = 1e12;
inline constexpr double kMinRecordInterval = 1e-12;
inline constexpr double kMaxOutlierRatio = 1e12;
/// How far a sampling interval may be from the mean one, relative (what a CSV
/// written with ten significant digits keeps).
inline constexpr double kUniformSamplingTolerance = 1e-6;

/// How the input behaves between samples (MATLAB's iddata InterSample):
/// held (ZOH, what a sampled controller or the trio's plant does), or linear
/// from one sample to the next (FOH, for an input that was continuous, such
/// as a sampled chirp).
enum class Intersample { kZoh, kFoh };
/// The model's state when the record starts. kZero: at rest at the operating
/// point (x = 0, the input before t[0] at u0). kSteadyState: at rest with the
/// first input sample u[0] applied since long before (the same as kZero when
/// u0 = u[0], the default). kEstimate: any state, fitted with the model (the
/// least-squares combination of its free responses for every parameter
/// vector), the input before t[0] at u[0]: a record cut from a run in motion.
enum class InitialCondition { kZero, kSteadyState, kEstimate };
bool ParseIntersample(const std::string& s, Intersample* v);
bool ParseInitialCondition(const std::string& s, InitialCondition* v);
std::string ToString(Intersample v);       // "zoh", "foh"
std::string ToString(InitialCondition v);  // "zero", "steady-state", "estimate"

/// The loss on each residual r_k: the cost is 1/2 sum rho(r_k^2), with rho
/// Ceres's (ceres::HuberLoss, ceres::CauchyLoss of scale a): kL2 rho(s) = s
/// (least squares); kHuber s for |r| <= a, 2 a |r| - a^2 beyond; kCauchy
/// a^2 log(1 + s / a^2). docs/identify.md, "Robust losses for dropouts".
enum class Loss { kL2, kHuber, kCauchy };
bool ParseLoss(const std::string& s, Loss* v);
std::string ToString(Loss v);  // "l2", "huber", "cauchy"
/// The default scale a of a robust loss is this many robust standard
/// deviations (1.4826 times the median absolute deviation) of the residuals
/// of the l2 fit: 95 % efficiency on Gaussian noise (Huber's 1.345, Holland
/// and Welsch's 2.385 for Cauchy).
inline constexpr double kHuberScaleInSigmas = 1.345;
inline constexpr double kCauchyScaleInSigmas = 2.385;
/// A sample whose weight rho'(r_k^2) is below this is listed as
/// down-weighted (IdentifyResult::downweighted).
inline constexpr double kDownweightedBelow = 0.5;

/// The most starts a fit takes (IdentifyOptions::starts).
inline constexpr int kMaxStarts = 1000;
/// The default and the range of IdentifyOptions::max_samples: a fit's time
/// grows with the samples (at 10000, about 0.6 s for P1D and 20 s for P2DU
/// or P2DZ on this project's 2 shared cores, when every start runs on all of
/// them: bench/identify_long_bench.sh), so a longer record is decimated
/// first (DecimateRecord) or refused.
inline constexpr std::size_t kDefaultMaxSamples = 10000;
inline constexpr std::size_t kMinMaxSamples = 100;
inline constexpr std::size_t kMaxMaxSamples = 10000000;
/// A record decimated to max_samples has its starts run on an eighth of
/// them (IdentifyOptions::start_samples), a TF's on a quarter (its
/// coefficients' starts on an eighth found a worse optimum: docs/identify.md,
/// "Long records"), at least kMinMaxSamples.
inline constexpr std::size_t kStartSamplesDivisor = 8;
inline constexpr std::size_t kTfStartSamplesDivisor = 4;
inline std::size_t StartSamples(std::size_t max_samples, bool tf = false) {
  return std::max(kMinMaxSamples, max_samples / (tf ? kTfStartSamplesDivisor : kStartSamplesDivisor));
}

struct IdentifyOptions {
  /// Starts of the multi-start design (Sobol' points over the time constants,
  /// Zeta and the delay, optim/sobol.h), in [1, kMaxStarts].
  int starts = 16;
  /// The design's digital shift (SobolSequence(d, seed)); 0: the unshifted
  /// sequence, whose first start is the lower corner of every range.
  std::uint64_t seed = 0;
  /// Also start from an ARX least-squares estimate (the poles of a linear
  /// regression of y on its past and on u delayed by the best of a scan),
  /// before the design's starts.
  bool arx_start = true;
  /// Also start from the optimum of the model this kind contains (P2D from
  /// P1D's, P2DU and P2DZ from P2D's), fitted first: a bigger model is then
  /// never worse than the smaller one it contains.
  bool nested_starts = true;
  /// After the starts, profile the delay (Td held at 0, at fractions of the
  /// best Td and at half samples around it, the rest refitted) and polish
  /// from the lowest: the cost has kinks where Td crosses a sample, and a
  /// start may stop at one, or short of Td = 0. Process models only.
  bool delay_profile = true;
  /// Then, if parameters end at a bound (Td at 0, Zeta at 1, a time constant
  /// at dt / 1000, ...), hold them there and refit the others: Ceres projects
  /// its steps onto the bounds and can stall there short of the optimum.
  /// Process models only.
  bool bounds_refit = true;
  /// The delay's upper bound as a fraction of the record's length, in (0, 1).
  double max_delay_fraction = 0.5;
  /// Levenberg-Marquardt iterations per start, >= 1.
  int max_iterations = 200;
  /// The operating point subtracted from u and y. u0 NaN: the first sample
  /// of u (the record starts at rest). y0 NaN: estimated with the model (an
  /// output offset fitted from y[0] as its start), so that the noise of one
  /// sample does not shift every residual.
  double u0 = std::numeric_limits<double>::quiet_NaN();
  double y0 = std::numeric_limits<double>::quiet_NaN();
  /// Also estimate u0 (MATLAB's InputOffset 'estimate'), from u0 (or the
  /// first sample) as its start: for an integrating model the input's bias
  /// is seen as a ramp; for the others it is seen in the transient of a
  /// record that does not start at rest at u0.
  bool estimate_u0 = false;
  /// The kind TF's numbers of poles (1..kMaxTfPoles) and zeros (0..poles-1);
  /// both 0 for every other kind (Identify refuses them otherwise).
  int poles = 0;
  int zeros = 0;
  Intersample intersample = Intersample::kZoh;
  InitialCondition initial_condition = InitialCondition::kZero;
  /// The loss on each residual (Loss): kL2, or kHuber or kCauchy for records
  /// with outliers (a sensor's dropouts).
  Loss loss = Loss::kL2;
  /// The robust loss's scale a, in units of y: finite, > 0, at most 1e12,
  /// and only with kHuber or kCauchy. NaN: derived from the record (the l2
  /// fit first, then kHuberScaleInSigmas or kCauchyScaleInSigmas times the
  /// robust standard deviation of its residuals).
  double loss_scale = std::numeric_limits<double>::quiet_NaN();
  /// Called after each start of the fit (on the caller's thread): the kind
  /// being fitted, the starts done and planned (the ARX start included), and
  /// the best cost so far. Empty: nothing is called. A front end shows
  /// progress with it; the library prints nothing.
  std::function<void(ProcessModelKind kind, int done, int total, double best_cost)> progress;
  /// Asked before every start and at every iteration of every solve (on the
  /// caller's thread); true stops the fit, which returns kRunnerFailed
  /// "cancelled". Empty: never cancelled. The page's identify_cancel.
  std::function<bool()> cancelled;
  /// The most samples a record may have, in [kMinMaxSamples, kMaxMaxSamples]:
  /// Identify refuses a longer one naming the limit; front ends decimate it
  /// to fit first (DecimateRecord).
  std::size_t max_samples = kDefaultMaxSamples;
  /// 0: the starts run on the record. Else, in [kMinMaxSamples,
  /// kMaxMaxSamples]: a model's starts (and its contained model's)
  /// run on a longer record decimated to at most this many samples
  /// (DecimateRecord), and only their best is refitted on the record itself,
  /// then refined as usual; starts and start_costs are then the decimated
  /// record's. RunIdentify sets it to an eighth of max_samples
  /// (kStartSamplesDivisor) for a record it decimated (docs/identify.md,
  /// "Long records"); a record within it is fitted as without.
  std::size_t start_samples = 0;

  /// Names the field, its value and the rule on failure.
  bool IsValid(std::string* error) const;
};

/// Whether the residuals look like white noise: their normalised
/// autocorrelation r_k = sum e_i e_{i+k} / sum e_i^2 at lags 1..lags, the 95 %
/// band +-1.96/sqrt(N) of white noise, and the Ljung-Box statistic
/// Q = N (N + 2) sum r_k^2 / (N - k), chi-square with `lags` degrees of
/// freedom when the residuals are white (MATLAB's resid draws the same band).
struct Whiteness {
  int lags = 0;
  std::vector<double> autocorrelation;  // r_1 .. r_lags
  double band = 0.0;                    // 1.96 / sqrt(N)
  int outside_band = 0;                 // lags with |r_k| > band
  double ljung_box_q = 0.0;
  double p_value = std::numeric_limits<double>::quiet_NaN();  // P(chi2_lags > Q)
  bool white = false;                                         // p_value >= 0.05
};

/// The whiteness of `residuals` over min(25, N / 4) lags (at least 1).
Whiteness ResidualWhiteness(const std::vector<double>& residuals);

struct IdentifyResult {
  ProcessModel model;
  std::vector<std::string> names;  // ParameterNames(model.kind)
  std::vector<double> values;      // ParameterValues(model)
  /// Standard errors of `values` from Ceres's covariance scaled by the
  /// residual variance 2 cost / (N - p); NaN when the covariance failed.
  std::vector<double> standard_errors;
  /// Their covariance, p x p row-major in the order of `names` (the matrix
  /// whose diagonal gives `standard_errors`); NaN when it failed.
  std::vector<double> covariance;
  bool covariance_ok = false;
  std::string covariance_message;  // why it failed, else empty
  double cost = 0.0;               // 1/2 sum rho(r_k^2): of squared residuals for l2
  double fit_percent = 0.0;        // 100 (1 - |y - yhat| / |y - mean y|)
  double aic = 0.0;                // N log(2 cost / N) + 2 p (p with y0 if estimated)
  double u0 = 0.0, y0 = 0.0;       // the operating point used
  /// How u0 was found, in words: "given", "estimated", "the first sample of
  /// u", or, when u0 was not given and the record's u[0] is not 0, the
  /// hypothesis chosen by AIC ("at rest at u = 0 before the record (AIC ...;
  /// at rest under u[0] = ...: AIC ...)").
  std::string u0_source;
  /// The hypotheses on the input the record rested at, fitted when u0 was
  /// not given (u0 = u[0], then u0 = 0): empty otherwise.
  struct RestHypothesis {
    double u0 = 0.0;
    double aic = std::numeric_limits<double>::quiet_NaN();  // NaN if it could not be fitted
    std::string message;                                    // why not, else empty
  };
  std::vector<RestHypothesis> rest_hypotheses;
  /// The loss the fit minimised, its scale a (NaN for kL2) and where that
  /// came from ("given", or the robust standard deviation it was derived
  /// from). `cost` is 1/2 sum rho(r_k^2) with this loss.
  Loss loss = Loss::kL2;
  double loss_scale = std::numeric_limits<double>::quiet_NaN();
  std::string loss_scale_source;
  /// rho'(r_k^2) at every sample (1 throughout for kL2), and the samples
  /// whose weight is below kDownweightedBelow, in order.
  std::vector<double> weights;
  std::vector<int> downweighted;
  bool y0_estimated = false;                                            // y0 was a parameter of the fit
  double y0_standard_error = std::numeric_limits<double>::quiet_NaN();  // if estimated
  bool u0_estimated = false;                                            // u0 was a parameter of the fit
  double u0_standard_error = std::numeric_limits<double>::quiet_NaN();  // if estimated
  double dt_s = 0.0;  // the sampling interval found (the mean one)
  Sampling sampling;  // uniform or not, the shortest and longest interval
  Intersample intersample = Intersample::kZoh;
  InitialCondition initial_condition = InitialCondition::kZero;
  /// x(t[0]) the fit used, in the coordinates of plant_sim::Realize(model's
  /// transfer function): fitted with kEstimate, -A^-1 B (u[0] - u0) with
  /// kSteadyState, zeros with kZero.
  std::vector<double> initial_state;
  int samples = 0;                      // N
  int starts = 0;                       // starts run: the design's, plus the ARX start if used
  bool arx_start = false;               // start_costs[0] is the ARX start
  std::uint64_t seed = 0;               // the design's shift (IdentifyOptions::seed)
  int starts_at_best = 0;               // starts whose cost is the best's within 1e-8 relative
  std::vector<double> start_costs;      // final cost of every start, in design order
  int nested_starts = 0;                // starts from a contained model's optimum (after the ARX start)
  /// The design's starts not run: IdentifyAuto skipped them once a quarter
  /// were done with the best AIC still more than 10 above another kind's.
  int starts_skipped = 0;
  bool delay_profile_improved = false;  // the delay's profile found a lower cost than every start
  bool bounds_refit_improved = false;   // holding the parameters at a bound, the rest refitted, lowered it
  /// For each parameter, "lower" or "upper" if it is at (within 1e-6 of) a
  /// bound of the fit (Td at 0, Zeta at 1, a time constant at dt / 1000),
  /// else "": its standard error is then NaN (a one-sided interval).
  std::vector<std::string> at_bound;
  /// The model's output y0 + yhat_k at every sample, and y_k - that.
  std::vector<double> simulated, residuals;
  Whiteness whiteness;
  /// The parameters the record does not identify: one at a bound of the fit
  /// (Td at 0 excepted: a record without dead time), a lag under a tenth of
  /// dt with no standard error or an interval wider than it, a time
  /// constant or Tz beyond kUnboundedRecordLengths times the record (an
  /// unbounded optimum). Each is also said in `warnings`, with the smaller
  /// model that describes the record without it.
  struct NotIdentifiable {
    std::string parameter;      // as in `names`
    std::string reason;         // "2.2e-06 s, under a tenth of dt = 0.002 s, with no standard error"
    std::string simpler_model;  // the kind without it ("p1d"), or "" if none of the process kinds
  };
  std::vector<NotIdentifiable> not_identifiable;
  /// Plain sentences on what the data leave undetermined: a parameter whose
  /// 95 % interval is wider than its value, residuals that are not white, a
  /// delay or time constant at its bound, no covariance.
  std::vector<std::string> warnings;
};

/// A time constant (or P2DZ's |Tz|) beyond this many record lengths is an
/// unbounded optimum: over the record its pole is an integrator's, and Kp
/// and it are known only as their ratio.
inline constexpr double kUnboundedRecordLengths = 100.0;
/// A lag under this fraction of dt whose interval is undetermined cannot be
/// told from a delay of its length.
inline constexpr double kUnresolvedLagOfDt = 0.1;

/// `pidlab identify --model auto`: every kind fitted, one chosen by AIC
/// (IdentifyAuto), and why in one sentence.
struct AutoCandidate {
  ProcessModelKind kind = ProcessModelKind::kP1D;
  Status status;  // of Identify for this kind
  IdentifyResult result;
  /// Why auto does not choose it, in words ("Tp2 is not identifiable (...)",
  /// or that it cannot beat the lowest AIC), else empty.
  std::string set_aside;
};
struct AutoResult {
  std::vector<AutoCandidate> candidates;  // in the order of the kinds
  int chosen = -1;                        // index into candidates
  std::string reason;
};

/// Status kInvalidInput with one plain message naming the reason unless the
/// record has at least kMinSamples samples, equal lengths, only finite
/// values within kMaxRecordMagnitude, t strictly increasing by at least
/// kMinRecordInterval, no u or y sample beyond kMaxOutlierRatio times its
/// column's median absolute deviation from the median. A constant u is not
/// refused here: with a given u0 it is a step (Identify refuses it otherwise).
/// Names the column and the sample:
/// its line in the file where `rows` gives each sample's (ReadCsvData), else
/// its index. Sets *sampling.
Status CheckData(const IdentifyData& data, Sampling* sampling, const std::vector<long>* rows = nullptr);
/// How DecimateRecord shortened a record: factor 1 when it was within the
/// limit (the record unchanged).
struct Decimation {
  int factor = 1;
  std::size_t samples_read = 0;  // before
  std::size_t samples = 0;       // after
  std::size_t max_samples = 0;   // the limit applied
  /// The fit's IdentifyOptions::start_samples that RunIdentify set (an
  /// eighth of the limit when factor > 1, else 0: the starts on the record).
  std::size_t start_samples = 0;
};

/// `data` (checked by CheckData) into *out, decimated by the least integer
/// factor q that leaves at most max_samples samples: sample k of *out is
/// sample k q of `data` in time, u its average over [t_kq, t_(k+1)q)
/// weighted by time (a held input's integral kept; with kFoh, a sampled
/// continuous input, the centred average as y's), y the average of the
/// samples centred on t_kq (at most q of them, symmetric, so no shift): an
/// anti-alias average. Sound while the dynamics are slow against q dt
/// (docs/identify.md, "Long records"). kInvalidInput naming the limit when
/// max_samples is out of [kMinMaxSamples, kMaxMaxSamples].
Status DecimateRecord(const IdentifyData& data, std::size_t max_samples, Intersample hold, IdentifyData* out,
                      Decimation* decimation);
/// The factor DecimateRecord takes: the least integer q with ceil(samples /
/// q) <= max_samples (1 within the limit).
std::size_t DecimationFactor(std::size_t samples, std::size_t max_samples);

/// kInvalidInput unless y varies beyond 12 digits of its magnitude: a flat
/// record holds no response to fit (Identify checks it after CheckData and
/// the model's own conditions, before any start).
Status CheckResponse(const IdentifyData& data);

/// yhat_k (without y0) of `model` for the input u - u0 sampled every dt_s.
/// Throws std::invalid_argument if the model is not a valid plant.
std::vector<double> SimulateModel(const ProcessModel& model, const std::vector<double>& u, double u0,
                                  double dt_s);

/// Fits a model of `kind` to `data`. kInvalidInput for bad data or options
/// (CheckData, IdentifyOptions::IsValid, poles and zeros as they say);
/// kRunnerFailed if no start converged. When u0 is neither given nor
/// estimated, the initial condition is kZero, u varies and u[0] != 0, the
/// record is fitted at rest under u[0] and at rest at u = 0, and the lower
/// AIC is kept (IdentifyResult::u0_source says which). A robust loss without
/// a scale is preceded by the l2 fit that gives its scale.
Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                IdentifyResult* result);
/// The same, with the fit of the model `kind` contains given (nullptr: none):
/// IdentifyAuto passes the kinds it fitted before. One fit: u0 as the options
/// say (NaN: the first sample, no hypotheses), and a robust loss needs its
/// loss_scale (kInvalidInput otherwise).
Status Identify(const IdentifyData& data, ProcessModelKind kind, const IdentifyOptions& options,
                const IdentifyResult* contained, IdentifyResult* result);

/// A pole of the identified model with the standard errors of its real and
/// imaginary parts (the delta method: the parameters' covariance carried
/// through the pole's derivatives, taken by central differences).
struct PoleEstimate {
  double re = 0.0, im = 0.0;
  double re_se = std::numeric_limits<double>::quiet_NaN();
  double im_se = std::numeric_limits<double>::quiet_NaN();
};

/// The poles of `result.model` (roots of its denominator, the upper one of a
/// complex pair first), with standard errors when the covariance is ok.
std::vector<PoleEstimate> PoleEstimates(const IdentifyResult& result);

/// IdentifyAuto runs the starts of a record longer than this on it decimated
/// to this many samples (IdentifyOptions::start_samples), unless the options
/// set start_samples.
inline constexpr std::size_t kAutoStartSamples = 2500;

/// Fits every process kind (P1D, P2D, P2DU, P1DI, P2DZ; not TF), each at the
/// rest Identify would choose (both rests fitted, the lower AIC kept per
/// kind) and with one loss scale for all (from the l2 fit auto chooses), and
/// chooses the lowest AIC, or,
/// among the kinds within 2 of it (which the data hardly tell apart), the one
/// of fewest parameters (then the lowest AIC among those).
/// kInvalidInput as Identify; kRunnerFailed if no kind could be fitted.
Status IdentifyAuto(const IdentifyData& data, const IdentifyOptions& options, AutoResult* result);

}  // namespace pidlab::identify
