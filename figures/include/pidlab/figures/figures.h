#pragma once
// The figures of `pidlab plot` as a library: the loop figure of an evaluation and of the
// episodes of an LCM log.

#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/identify/identify.h"
#include "pidlab/plot/plot.h"
#include "pidlab/spec/status.h"

namespace pidlab::figures {

/// One trace per gain set. The sampled loop records every step (y, e, u, n at
/// t = k dt); the continuous loop has no sampled command, so y, e, n are drawn
/// at the sample times t = m ts and the title says so. A failed Status (kInvalidInput) for
/// invalid input.
Status EvaluationFigure(const Plant& plant, const std::vector<PidGains>& gains,
                        const evaluation::LoopOptions& options, plot::Figure* figure);

/// One trace per episode of the log (all, or those listed in `episodes`).
/// *report receives the reader's warnings (one line each). A failed Status (kInvalidInput)
/// if the log cannot be read or holds no matching episode.
Status LogFigure(const std::string& log_path, const std::vector<long>& episodes, plot::Figure* figure,
                 std::string* report);

/// `pidlab identify --plot`: the measured output and the model's, the
/// residuals, and their autocorrelation with the 95 % band of white noise
/// (three panels). A failed Status (kInvalidInput) if the result has no simulated output.
Status IdentifyFigure(const identify::IdentifyData& data, const identify::IdentifyResult& result,
                      plot::Figure* figure);

}  // namespace pidlab::figures
