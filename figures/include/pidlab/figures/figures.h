#pragma once
// The figures of `pidlab plot` as a library: the loop figure of an evaluation and of the
// episodes of an LCM log.

#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/identify/identify.h"
#include "pidlab/plot/plot.h"

namespace pidlab::figures {

/// One trace per gain set. The sampled loop records every step (y, e, u, n at
/// t = k dt); the continuous loop has no sampled command, so y, e, n are drawn
/// at the sample times t = m ts and the title says so. False with *error for
/// invalid input.
bool EvaluationFigure(const Plant& plant, const std::vector<PidGains>& gains,
                      const evaluation::LoopOptions& options, plot::Figure* figure, std::string* error);

/// One trace per episode of the log (all, or those listed in `episodes`).
/// *report receives the reader's warnings (one line each). False with *error
/// if the log cannot be read or holds no matching episode.
bool LogFigure(const std::string& log_path, const std::vector<long>& episodes, plot::Figure* figure,
               std::string* report, std::string* error);

/// `pidlab identify --plot`: the measured output and the model's, the
/// residuals, and their autocorrelation with the 95 % band of white noise
/// (three panels). False with *error if the result has no simulated output.
bool IdentifyFigure(const identify::IdentifyData& data, const identify::IdentifyResult& result,
                    plot::Figure* figure, std::string* error);

}  // namespace pidlab::figures
