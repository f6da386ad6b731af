#pragma once
// A starting point for the output-error fit from a linear least-squares ARX
// estimate (as MATLAB's procest initialises): identify.cc, internal.

#include <complex>
#include <vector>

#include "pidlab/identify/process_model.h"

namespace pidlab::identify::internal {

/// One ARX model
///   y_j + a_1 y_(j-1) + ... + a_n y_(j-n) = b_1 u_(j-1-d) + ... + b_n u_(j-n-d)
/// fitted by linear least squares to the record taken every m samples (u
/// averaged over each coarse interval): its n discrete poles z (roots of
/// z^n + a_1 z^(n-1) + ... + a_n), its sampling interval h = m dt and its
/// delay d h.
struct ArxFit {
  std::vector<std::complex<double>> z;
  double h_s = 0.0, td_s = 0.0;
};

/// Every ARX model of order `poles` (>= 1) over m = 1, 2, 4, ... while 40 n
/// coarse samples remain, for delays d of up to max_delay_s (about 40 values
/// per m). Coarser sampling resolves slow or lightly damped poles that noise
/// hides at the record's own rate.
std::vector<ArxFit> ArxFits(int poles, const std::vector<double>& du, const std::vector<double>& dy,
                            double dt_s, double max_delay_s);

/// Candidate parameter values (order of ParameterNames, Kp left at 1: the
/// caller sets it and scores each) of `kind` (not TF: tf_start.h), each read
/// off one of ArxFits(n) (n the kind's number of poles), Td = d m dt.
/// Candidates whose poles the kind cannot take are left out.
std::vector<std::vector<double>> ArxCandidates(ProcessModelKind kind, const std::vector<double>& du,
                                               const std::vector<double>& dy, double dt_s,
                                               double max_delay_s);

}  // namespace pidlab::identify::internal
