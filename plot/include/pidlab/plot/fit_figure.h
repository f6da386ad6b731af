#pragma once
// The figure of a model fitted to a record (`pidlab identify --plot`, the
// report's "Identifying the motor"): the measured output with the model's,
// the residuals, and their autocorrelation with the 95 % band of white noise.

#include <string>
#include <vector>

#include "pidlab/plot/plot.h"

namespace pidlab::plot {

struct FitTrace {
  std::vector<double> t, measured, simulated, residuals;
  std::vector<double> autocorrelation;  // r_1 .. r_lags
  double band = 0.0;                    // 1.96 / sqrt(N)
};

/// Three panels into *figure (title left to the caller). A failed Status (kInvalidInput)
/// if the lengths disagree or there is no autocorrelation.
Status MakeFitFigure(const FitTrace& trace, const std::string& output_label, Figure* figure);

}  // namespace pidlab::plot
