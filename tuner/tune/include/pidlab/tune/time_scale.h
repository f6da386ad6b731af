// Time scales from the closed loop of given gains (issue 40, "Time scales
// from the plant"): what `pidlab evaluate` and `pidlab plot` sample when
// neither --horizon nor --sample-time is given.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/migo.h"

namespace pidlab::tune {

/// LoopTimeScale of the closed loops of `gains` on `plant`: the slowest
/// closed-loop time constant over the sets, the fastest of the plant's times
/// and 1/gain crossover. Where no set gives a stable, analysed loop, the
/// plant's own times (PlantTimes). source "plant"; reason says which.
TimeScale GainsTimeScale(const Plant& plant, const std::vector<PidGains>& gains,
                         const evaluation::LoopOptions& loop);

/// The sampled loop's grid, in one place for every front end (evaluate,
/// plot, serve, a time scale derived or framed): the spacing a whole
/// multiple of dt_s, at least dt_s, and the horizon a whole multiple of the
/// spacing, rounded up. Nothing changes when dt_s is not a positive finite
/// number (the continuous loop, or a dt its caller refuses).
void OnSampledGrid(double dt_s, double* sample_time_s, double* horizon_s);

/// The sampled loop's period for a plant when none is given (autotune):
/// min(L, the plant's fastest time) / kDtPerFastestTime, rounded down to a
/// 1-2-5 value, and at least L / kMaxAnalysedDelaySteps (rounded up) so
/// that the delay line stays analysable. *why says which, in one line.
inline constexpr double kDtPerFastestTime = 400.0;
double SampledDtFromPlant(const Plant& plant, std::string* why);

/// SampledDtFromPlant on a spec (autotune): off the paper's plants and
/// unless dt is in *given, the spec's dt from its plant's time scales (the
/// plant built on the noiseless continuous loop, which takes any delay), and
/// its sample time and horizon on that grid unless given; "dt" joins *given.
/// Returns the line that says so, or "" (nothing derived).
std::string SampledDtFromSpec(spec::EvaluateSpec* s, std::set<std::string>* given);

/// The relay's default y limit for a plant when none is given (autotune,
/// `--y-limit`; docs/autotune.md, "Settings from the process"): the span of
/// |y - y0| from the hold's level beyond which the relay stops. It is
/// kRelayYLimitAmplitudes times the relay's expected amplitude, the
/// describing function's 4 d / (pi Ku) for a relay of d (the larger of its
/// two sides) on the plant's ultimate gain Ku (a reverse-acting plant's
/// mirror's); where the plant has no ultimate gain, twice its static
/// response |K| d; +inf where it has neither (or is nonlinear). *why says
/// which, in one line. A measurement noise of standard deviation sigma
/// (the simulated process's) widens it by kRelayYLimitSigmas sigma.
inline constexpr double kRelayYLimitAmplitudes = 10.0;
inline constexpr double kRelayYLimitSigmas = 6.0;
double RelayYLimitFromPlant(const Plant& plant, double d, double noise_sigma, std::string* why);

/// Which loops take a derived time scale.
enum class TimeScaleScope {
  kNotPaper,  ///< every plant but the paper's (evaluate: eq. 4's numbers stay)
  /// Every plant, framed for a figure (plot: not a published number): the
  /// horizon cut to 3 x the slowest 2 % settling time of the sets' step
  /// responses plus the dead time, rounded up, the spacing at most a 500th
  /// of it, so that the transient fills the frame.
  kFigure,
};

/// With neither `horizon` nor `sample_time` in `given` and the plant in
/// `scope`, sets loop->horizon_s and loop->sample_time_s to GainsTimeScale
/// (the spacing a multiple of dt on the sampled loop) and returns it. Else
/// the loop's own: "eq. (4)" when it is eq. (4)'s on a paper plant, "given"
/// otherwise (or the derived one, when the given loop has its numbers: a
/// result's echo). A loop that does not build keeps its own (its caller
/// reports it).
/// An evaluation of `gains` on `loop` (of the same plant, the in-process
/// runner, step info computed) that the caller already has: kFigure's frame
/// reads its settling time where the frame's loop is that loop bit for bit
/// (evaluation::LoopOptionsKey), instead of evaluating it again. The step
/// info does not depend on the other EvaluateOptions.
struct KnownEvaluation {
  const PidGains* gains = nullptr;
  const evaluation::LoopOptions* loop = nullptr;
  const evaluation::Evaluation* evaluation = nullptr;
  bool Matches(const PidGains& g, const evaluation::LoopOptions& l) const;
};

TimeScale ResolveGainsTimeScale(const spec::PlantSpec& plant_spec, const Plant& plant,
                                const std::vector<PidGains>& gains, const std::set<std::string>& given,
                                TimeScaleScope scope, spec::LoopSpec* loop,
                                const KnownEvaluation& known = {});

}  // namespace pidlab::tune
