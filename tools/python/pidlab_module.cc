// pidlab from Python (docs/python.md): pidlab.evaluate and pidlab.tune,
// returning the dicts of `pidlab evaluate --json` and `pidlab tune --json`
// (the same code builds them: pidlab::json, tools/json/). The extension is
// pidlab._pidlab; the package pidlab (with the lcm-gen'd messages) imports
// evaluate and tune from it.
//
// Flags become keyword arguments with the flag's name (--sample-time ->
// sample_time). Bad input raises ValueError with the CLI's one-line message.

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "pidlab/json/results_json.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/tuner/evaluation.h"
#include "pidlab/tuner/tune.h"

namespace py = pybind11;

namespace pidlab::python {
namespace {

[[noreturn]] void Bad(const std::string& message) { throw py::value_error(message); }

/// The dict of a JSON object: through Python's json module, so the keys,
/// nulls and every double (dumped with 17 significant digits) are exactly
/// those of the command line's output.
py::object ToPython(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

/// A plant by name ("oscillator", "linear", ...) or as (num, den), or
/// "custom" with num= and den=.
Plant MakePlantArg(const py::object& plant, const std::optional<std::vector<double>>& num,
                   const std::optional<std::vector<double>>& den) {
  Plant p;
  std::string error;
  if (py::isinstance<py::str>(plant)) {
    const std::string name = plant.cast<std::string>();
    if (name == "custom") {
      if (!num || !den) Bad("plant 'custom' needs num= and den=");
      if (!MakeCustomPlant(*num, *den, &p, &error)) Bad(error);
    } else {
      if (num || den) Bad("num= and den= go with plant='custom' (or plant=(num, den)), not '" + name + "'");
      if (!MakePlant(name, StepperMotorParameters{}, &p, &error)) Bad(error);
    }
    return p;
  }
  std::vector<std::vector<double>> tf;
  try {
    tf = plant.cast<std::vector<std::vector<double>>>();
  } catch (const py::cast_error&) {
    Bad("plant must be a name or (num, den), two lists of numbers");
  }
  if (tf.size() != 2) Bad("plant (num, den) must have two lists, not " + std::to_string(tf.size()));
  if (!MakeCustomPlant(tf[0], tf[1], &p, &error)) Bad(error);
  return p;
}

PidGains MakeGains(const std::vector<double>& g) {
  if (g.size() != 3) Bad("gains must be (kp, ki, kd), not " + std::to_string(g.size()) + " numbers");
  PidGains gains{g[0], g[1], g[2]};
  std::string error;
  if (!GainsAreValid(gains, &error)) Bad(error);
  return gains;
}

/// The loop flags of `pidlab evaluate` / `tune` (tools/cli_common.cc, LoopFlags).
struct LoopArgs {
  std::string loop = "continuous";
  double dt = 1e-3, sample_time = 0.05, horizon = 25.0;
  std::optional<double> stability_margin;
  std::string disturbance;  // empty: square if an amplitude is given
  double disturbance_amplitude = 0.0, disturbance_period = 2.0, disturbance_phase = 0.0;
  double disturbance_step_time = 0.0, noise_hold = 0.01;
  std::uint64_t seed = 1;
  double derivative_filter = 0.0, derivative_filter_ratio = 0.0;
  std::optional<std::pair<double, double>> output_limits;
  std::string anti_windup = "clamping", derivative_on = "error", integral = "backward-euler";
  double reference = 1.0;  // --reference A

  LoopOptions Build(double default_margin) const {
    LoopOptions o;
    if (!ParseLoopKind(loop, &o.loop)) Bad("loop '" + loop + "' must be continuous or sampled");
    o.dt_s = dt;
    o.sample_time_s = sample_time;
    o.horizon_s = horizon;
    o.reference = reference;
    o.stability_margin = stability_margin.value_or(default_margin);
    DisturbanceOptions& d = o.disturbance;
    if (disturbance.empty())
      d.kind = disturbance_amplitude != 0.0 ? DisturbanceKind::kSquare : DisturbanceKind::kNone;
    else if (!ParseDisturbanceKind(disturbance, &d.kind))
      Bad("disturbance '" + disturbance + "' must be none, square, step, sine or noise");
    d.amplitude = disturbance_amplitude;
    d.period_s = disturbance_period;
    d.phase_s = disturbance_phase;
    d.step_time_s = disturbance_step_time;
    d.noise_hold_s = noise_hold;
    d.seed = seed;
    o.pid.dt_s = dt;
    o.pid.derivative_filter_s = derivative_filter;
    o.derivative_filter_ratio = derivative_filter_ratio;
    if (output_limits) {
      o.pid.output_min = output_limits->first;
      o.pid.output_max = output_limits->second;
    }
    if (!ParseAntiWindup(anti_windup, &o.pid.anti_windup))
      Bad("anti_windup '" + anti_windup + "' must be none, clamping or back-calculation");
    if (!ParseDerivativeOn(derivative_on, &o.pid.derivative_on))
      Bad("derivative_on '" + derivative_on + "' must be error or measurement");
    if (!ParseIntegralMethod(integral, &o.pid.integral))
      Bad("integral '" + integral + "' must be backward-euler, forward-euler or trapezoidal");
    std::string error;
    if (!o.IsValid(&error)) Bad(error);
    return o;
  }
};

/// The loop bounds of `pidlab evaluate` / `tune` (tools/cli_common.cc,
/// BoundsFlags): --max-ms -> max_ms, ...; None leaves a bound unset.
struct BoundsArgs {
  std::optional<double> max_ms, max_mt, max_noise_gain, min_phase_margin, min_gain_margin, max_time_constant;

  LoopBounds Build() const {
    LoopBounds b;
    if (max_ms) b.max_ms = *max_ms;
    if (max_mt) b.max_mt = *max_mt;
    if (max_noise_gain) b.max_noise_gain = *max_noise_gain;
    if (min_phase_margin) b.min_phase_margin_deg = *min_phase_margin;
    if (min_gain_margin) b.min_gain_margin = *min_gain_margin;
    if (max_time_constant) b.max_time_constant_s = *max_time_constant;
    std::string error;
    if (!b.IsValid(&error)) Bad(error);
    return b;
  }
};

py::object EvaluatePy(const py::object& plant, const std::vector<double>& gains, const LoopArgs& loop,
                      const BoundsArgs& bounds, const std::optional<std::vector<double>>& num,
                      const std::optional<std::vector<double>>& den) {
  const Plant p = MakePlantArg(plant, num, den);
  const PidGains g = MakeGains(gains);
  const LoopOptions options = loop.Build(LoopOptions{}.stability_margin);
  const LoopBounds loop_bounds = bounds.Build();
  Evaluation ev;
  std::string error;
  LoopAnalysis analysis;
  bool ok = false;
  {
    py::gil_scoped_release release;
    ok = Evaluate(p, g, options, EvaluateOptions{}, &ev, &error) &&
         AnalyzeLoop(p, g, options, LoopAnalysisOptions{}, &analysis, &error);
  }
  if (!ok) Bad(error);
  nlohmann::json j = json::ToJson(ev);
  j["backend"] = "local";
  j["robustness"] = json::RobustnessJson(analysis, loop_bounds);
  return ToPython(j);
}

struct TuneArgs {
  std::string method = "multi-start";
  std::optional<std::string> objective;  // None: iae, or --robust's with robust=True
  std::string zn_rule = "classic";
  std::pair<double, double> bounds{0.0, 30.0};
  int max_iterations = 0, max_evaluations = 0, starts = 4;
  bool adaptive = false, refine = true;
  double agree_tolerance = 1e-3;
  std::optional<double> max_overshoot, max_settling;
  int design_points = pidlab::TuneOptions{}.design_points,
      refine_starts = pidlab::TuneOptions{}.refine_starts;
  std::optional<double> load_weight;  // None: 1
  bool robust = false;
  int robust_samples = 0;
  double robust_quantile = 1.0, robust_spread = 0.1;
};

py::object TunePy(const py::object& plant, const LoopArgs& loop, const BoundsArgs& bounds,
                  const TuneArgs& args, const std::optional<std::vector<double>>& num,
                  const std::optional<std::vector<double>>& den) {
  const Plant p = MakePlantArg(plant, num, den);
  TuneOptions o;
  o.loop = loop.Build(TuneOptions::DefaultTuneLoop().stability_margin);
  if (!ParseTuneMethod(args.method, &o.method))
    Bad("method '" + args.method + "' must be nelder-mead, paper-nm, ziegler-nichols, ga or pso-gsa");
  const std::string objective = args.objective.value_or("iae");
  if (!ParseObjectiveKind(objective, &o.objective))
    Bad("objective '" + objective + "' must be iae, ise, itae, iae-continuous, load-iae or setpoint-load");
  if (!ParseZieglerNicholsRule(args.zn_rule, &o.zn_rule))
    Bad("zn_rule '" + args.zn_rule + "' must be classic, pessen, some-overshoot or no-overshoot");
  o.lower = args.bounds.first;
  o.upper = args.bounds.second;
  o.max_iterations = args.max_iterations;
  o.max_evaluations = args.max_evaluations;
  o.starts = args.starts;
  o.design_points = args.design_points;
  o.refine_starts = args.refine_starts;
  o.adaptive = args.adaptive;
  o.seed = loop.seed;
  o.refine = args.refine;
  o.agree_tolerance = args.agree_tolerance;
  const double inf = std::numeric_limits<double>::infinity();
  o.max_overshoot_pct = args.max_overshoot.value_or(inf);
  o.max_settling_time_s = args.max_settling.value_or(inf);
  o.load_weight = args.load_weight.value_or(1.0);
  o.bounds = bounds.Build();
  if (args.robust) {
    // As `pidlab tune --robust`: an argument given next to it overrides its part.
    RobustPresetKeep keep;
    keep.objective = args.objective.has_value();
    keep.load_weight = args.load_weight.has_value();
    keep.derivative_filter = loop.derivative_filter != 0.0 || loop.derivative_filter_ratio != 0.0;
    keep.max_ms = bounds.max_ms.has_value();
    keep.max_time_constant = bounds.max_time_constant.has_value();
    ApplyRobustPreset(&o, keep);
  }
  o.robust_samples = args.robust_samples;
  o.robust_quantile = args.robust_quantile;
  o.robust_spread = args.robust_spread;
  std::string error;
  if (!o.IsValid(&error)) Bad(error);
  TuneSummary s;
  Evaluation ev;
  LoopAnalysis analysis;
  bool ok = false;
  {
    py::gil_scoped_release release;
    ok = Tune(p, o, &s, &error);
    if (ok && s.stable) {
      Evaluate(p, s.gains, o.loop, EvaluateOptions{}, &ev, &error);
      ok = AnalyzeLoop(p, s.gains, o.loop, LoopAnalysisOptions{}, &analysis, &error);
    }
  }
  if (!ok) Bad(error);
  nlohmann::json j = json::TuneJson(p, o, s, ev, "local");
  j["robustness"] = s.stable ? json::RobustnessJson(analysis, o.bounds) : nlohmann::json(nullptr);
  return ToPython(j);
}

}  // namespace
}  // namespace pidlab::python

PYBIND11_MODULE(_pidlab, m) {
  using namespace pidlab::python;
  m.doc() =
      "pidlab: evaluate and tune PID gains (docs/python.md). Results are the dicts of "
      "`pidlab evaluate --json` and `pidlab tune --json`.";
  m.attr("__version__") = PIDLAB_VERSION;
  using OptVec = std::optional<std::vector<double>>;
  using OptPair = std::optional<std::pair<double, double>>;
  using OptDouble = std::optional<double>;
  m.def(
      "evaluate",
      [](const py::object& plant, const std::vector<double>& gains, const std::string& loop, double dt,
         double sample_time, double horizon, OptDouble stability_margin, const std::string& disturbance,
         double disturbance_amplitude, double disturbance_period, double disturbance_phase,
         double disturbance_step_time, double noise_hold, std::uint64_t seed, double derivative_filter,
         double derivative_filter_ratio, OptPair output_limits, const std::string& anti_windup,
         const std::string& derivative_on, const std::string& integral, double reference, const OptVec& num,
         const OptVec& den, OptDouble max_ms, OptDouble max_mt, OptDouble max_noise_gain,
         OptDouble min_phase_margin, OptDouble min_gain_margin, OptDouble max_time_constant) {
        const LoopArgs l{loop,
                         dt,
                         sample_time,
                         horizon,
                         stability_margin,
                         disturbance,
                         disturbance_amplitude,
                         disturbance_period,
                         disturbance_phase,
                         disturbance_step_time,
                         noise_hold,
                         seed,
                         derivative_filter,
                         derivative_filter_ratio,
                         output_limits,
                         anti_windup,
                         derivative_on,
                         integral,
                         reference};
        const BoundsArgs b{max_ms,           max_mt,          max_noise_gain,
                           min_phase_margin, min_gain_margin, max_time_constant};
        return EvaluatePy(plant, gains, l, b, num, den);
      },
      "Evaluates gains (kp, ki, kd) on a plant given by name ('double_integrator', 'oscillator', "
      "'stepper_motor', 'stepper_nonlinear' with Table I's defaults, and their aliases) or as (num, den) in "
      "descending powers of s. Returns the dict of `pidlab evaluate --json`; max_ms, max_mt, max_noise_gain, "
      "min_phase_margin, min_gain_margin and max_time_constant are the bound flags, reported in "
      "robustness.violations.",
      py::arg("plant"), py::arg("gains"), py::kw_only(), py::arg("loop") = "continuous", py::arg("dt") = 1e-3,
      py::arg("sample_time") = 0.05, py::arg("horizon") = 25.0, py::arg("stability_margin") = py::none(),
      py::arg("disturbance") = "", py::arg("disturbance_amplitude") = 0.0,
      py::arg("disturbance_period") = 2.0, py::arg("disturbance_phase") = 0.0,
      py::arg("disturbance_step_time") = 0.0, py::arg("noise_hold") = 0.01, py::arg("seed") = 1,
      py::arg("derivative_filter") = 0.0, py::arg("derivative_filter_ratio") = 0.0,
      py::arg("output_limits") = py::none(), py::arg("anti_windup") = "clamping",
      py::arg("derivative_on") = "error", py::arg("integral") = "backward-euler", py::arg("reference") = 1.0,
      py::arg("num") = py::none(), py::arg("den") = py::none(), py::arg("max_ms") = py::none(),
      py::arg("max_mt") = py::none(), py::arg("max_noise_gain") = py::none(),
      py::arg("min_phase_margin") = py::none(), py::arg("min_gain_margin") = py::none(),
      py::arg("max_time_constant") = py::none());
  m.def(
      "tune",
      [](const py::object& plant, const std::string& method, const std::optional<std::string>& objective,
         std::pair<double, double> bounds, int max_iter, int max_evals, int starts, bool adaptive,
         bool refine, double agree_tolerance, OptDouble max_overshoot, OptDouble max_settling,
         const std::string& zn_rule, int design_points, int refine_starts, const std::string& loop, double dt,
         double sample_time, double horizon, OptDouble stability_margin, const std::string& disturbance,
         double disturbance_amplitude, double disturbance_period, double disturbance_phase,
         double disturbance_step_time, double noise_hold, std::uint64_t seed, double derivative_filter,
         double derivative_filter_ratio, OptPair output_limits, const std::string& anti_windup,
         const std::string& derivative_on, const std::string& integral, double reference, const OptVec& num,
         const OptVec& den, OptDouble load_weight, bool robust, int robust_samples, double robust_quantile,
         double robust_spread, OptDouble max_ms, OptDouble max_mt, OptDouble max_noise_gain,
         OptDouble min_phase_margin, OptDouble min_gain_margin, OptDouble max_time_constant) {
        const LoopArgs l{loop,
                         dt,
                         sample_time,
                         horizon,
                         stability_margin,
                         disturbance,
                         disturbance_amplitude,
                         disturbance_period,
                         disturbance_phase,
                         disturbance_step_time,
                         noise_hold,
                         seed,
                         derivative_filter,
                         derivative_filter_ratio,
                         output_limits,
                         anti_windup,
                         derivative_on,
                         integral,
                         reference};
        const BoundsArgs b{max_ms,           max_mt,          max_noise_gain,
                           min_phase_margin, min_gain_margin, max_time_constant};
        const TuneArgs t{method,        objective,      zn_rule,         bounds,        max_iter,
                         max_evals,     starts,         adaptive,        refine,        agree_tolerance,
                         max_overshoot, max_settling,   design_points,   refine_starts, load_weight,
                         robust,        robust_samples, robust_quantile, robust_spread};
        return TunePy(plant, l, b, t, num, den);
      },
      "Tunes PID gains for a plant (as for evaluate) and returns the dict of `pidlab tune --json`. The "
      "defaults are the command's (the multi-start search, the paper's loop, the Ceres cross-check). "
      "robust=True applies `pidlab tune --robust` (objective setpoint-load, load_weight 1, derivative filter "
      "ratio 10, Ms <= 1.6, time constant <= horizon/10); objective, load_weight, derivative_filter or "
      "derivative_filter_ratio, max_ms and max_time_constant given next to it override their part, as the "
      "flags do. max_ms, max_mt, max_noise_gain, min_phase_margin, min_gain_margin and max_time_constant are "
      "the bound flags (None: no bound); robust_samples, robust_quantile and robust_spread are "
      "--robust-samples, --robust-quantile and --robust-spread.",
      py::arg("plant"), py::kw_only(), py::arg("method") = "multi-start", py::arg("objective") = py::none(),
      py::arg("bounds") = std::make_pair(0.0, 30.0), py::arg("max_iter") = 0, py::arg("max_evals") = 0,
      py::arg("starts") = pidlab::TuneOptions{}.starts, py::arg("adaptive") = false, py::arg("refine") = true,
      py::arg("agree_tolerance") = 1e-3, py::arg("max_overshoot") = py::none(),
      py::arg("max_settling") = py::none(), py::arg("zn_rule") = "classic",
      py::arg("design_points") = pidlab::TuneOptions{}.design_points,
      py::arg("refine_starts") = pidlab::TuneOptions{}.refine_starts, py::arg("loop") = "continuous",
      py::arg("dt") = 1e-3, py::arg("sample_time") = 0.05, py::arg("horizon") = 25.0,
      py::arg("stability_margin") = py::none(), py::arg("disturbance") = "",
      py::arg("disturbance_amplitude") = 0.0, py::arg("disturbance_period") = 2.0,
      py::arg("disturbance_phase") = 0.0, py::arg("disturbance_step_time") = 0.0,
      py::arg("noise_hold") = 0.01, py::arg("seed") = 1, py::arg("derivative_filter") = 0.0,
      py::arg("derivative_filter_ratio") = 0.0, py::arg("output_limits") = py::none(),
      py::arg("anti_windup") = "clamping", py::arg("derivative_on") = "error",
      py::arg("integral") = "backward-euler", py::arg("reference") = 1.0, py::arg("num") = py::none(),
      py::arg("den") = py::none(), py::arg("load_weight") = py::none(), py::arg("robust") = false,
      py::arg("robust_samples") = 0, py::arg("robust_quantile") = 1.0, py::arg("robust_spread") = 0.1,
      py::arg("max_ms") = py::none(), py::arg("max_mt") = py::none(), py::arg("max_noise_gain") = py::none(),
      py::arg("min_phase_margin") = py::none(), py::arg("min_gain_margin") = py::none(),
      py::arg("max_time_constant") = py::none());
}
