#pragma once
// The general transfer function (ProcessModelKind::kTf) in the fit of
// identify.cc, internal. Its parameters theta are b_0..b_m, a_0..a_(n-1), Td
// as ParameterNames gives them: the coefficients in seconds, unbounded, Td
// bounded as every kind's. A TF whose denominator is not Hurwitz, or has
// an oscillation faster than the samples can show, is not a plant the fit
// may visit (its residuals fail), so the fit stays stable.
// The numerator enters the output linearly: every start sets it by linear
// least squares at its poles and delay.

#include <vector>

#include "pidlab/identify/process_model.h"
#include "pidlab/spec/status.h"

namespace pidlab::identify::internal {

/// kInvalidInput naming the value unless poles is in 1..kMaxTfPoles and
/// zeros in 0..poles-1 for kTf, or both are 0 for every other kind.
Status CheckTfShape(ProcessModelKind kind, int poles, int zeros);

/// Whether the fit may visit the denominator s^n + a_(n-1) s^(n-1) + ... +
/// a_0: Hurwitz, and no pole's imaginary part beyond the Nyquist frequency
/// pi / dt_s, whose oscillation the samples would alias to a slower one.
bool TfDenominatorIsAdmissible(const std::vector<double>& a, double dt_s);

/// Coefficients (every value but the last, Td) of magnitude below
/// kMinCoefficientMagnitude set to 0, as TransferFunction::IsValid asks.
void SnapTinyCoefficients(std::vector<double>* values);

/// The Sobol' design's dimensions for a tf of `poles` poles (optim/sobol.h
/// has at most 4): the slowest lag, the fastest (poles > 1) and Td.
int TfDesignDimensions(int poles);

/// `poles` lags log-spaced from the slowest, exp(lo + h_slow (hi - lo)),
/// down to the fastest, exp(lo + h_fast (log slowest - lo)) (h in [0, 1)):
/// real poles spread over the record's time scales in two coordinates,
/// whatever their number.
std::vector<double> SpreadLags(int poles, double h_slow, double h_fast, double lo, double hi);

/// theta's denominator a_0..a_(n-1) (after the zeros + 1 numerator
/// coefficients) from the lags: prod (s + 1 / tau_i).
void SetDenominatorFromLags(int zeros, const std::vector<double>& taus_s, std::vector<double>* theta);

/// theta's numerator b_0..b_m (and theta[p], the output offset, if
/// `offset`) by linear least squares on dy at theta's denominator and
/// delay. Without a solution (an unstable denominator, a singular
/// regression) b_0 = a_0 (a unit static gain), the rest 0.
void SetNumeratorByLeastSquares(int poles, int zeros, const std::vector<double>& du,
                                const std::vector<double>& dy, double dt_s, bool offset,
                                std::vector<double>* theta);

/// Candidate values (b, a, Td; b left for SetNumeratorByLeastSquares) from
/// the ARX models of order `poles` (arx_start.h): each discrete pole z mapped
/// to s = log(z) / h, the denominator prod (s - s_i) kept if it is real and
/// Hurwitz.
std::vector<std::vector<double>> TfArxCandidates(int poles, int zeros, const std::vector<double>& du,
                                                 const std::vector<double>& dy, double dt_s,
                                                 double max_delay_s);

}  // namespace pidlab::identify::internal
