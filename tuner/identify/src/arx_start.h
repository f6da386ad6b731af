#pragma once
// A starting point for the output-error fit from a linear least-squares ARX
// estimate (as MATLAB's procest initialises): identify.cc, internal.

#include <vector>

#include "pidlab/identify/process_model.h"

namespace pidlab::identify::internal {

/// Candidate parameter values (order of ParameterNames, Kp left at 1: the
/// caller sets it and scores each) of `kind`, each read off an ARX model
///   y_j + a_1 y_(j-1) + ... + a_n y_(j-n) = b_1 u_(j-1-d) + ... + b_n u_(j-n-d)
/// (n the kind's number of poles) fitted by linear least squares to the
/// record taken every m samples (m = 1, 2, 4, ... while 40 n coarse samples
/// remain; u averaged over each coarse interval), for delays d of up to
/// max_delay_s (about 40 values per m); Td = d m dt. Coarser sampling
/// resolves slow or lightly damped poles that noise hides at the record's
/// own rate. Candidates whose poles the kind cannot take are left out.
std::vector<std::vector<double>> ArxCandidates(ProcessModelKind kind, const std::vector<double>& du,
                                               const std::vector<double>& dy, double dt_s,
                                               double max_delay_s);

}  // namespace pidlab::identify::internal
