#include "pidlab/tune/problem.h"

#include <cmath>
#include <complex>
#include <sstream>
#include <utility>

#include "pidlab/spec/field.h"
#include "pidlab/spec/json.h"
#include "pidlab/tune/design.h"
#include "pidlab/tune/time_scale.h"
#include "pidlab/tune/tuning_rules.h"
#include "pidlab/tune/two_dof.h"
#include "rejections.h"
#include "spec_build.h"

namespace pidlab::tune {

using spec::DisplayName;
using spec::NameStyle;
using spec::Quote;

namespace {

// A step's bool + message as the edge's Status.
Status Checked(bool ok, const std::string& error) { return ok ? Status::Ok() : Status::InvalidInput(error); }

// The refusals of Monte Carlo draws for this plant on this backend.
Status CheckMonteCarlo(const EvaluationProblem& p, const BuildOptions& options) {
  const auto name = [&options](const char* key) { return DisplayName(key, options.style); };
  if (!p.HasMonteCarlo()) return Status::Ok();
  if (options.backend == Backend::kRunner)
    return Status::InvalidInput(name("monte_carlo") + " runs in process: use " + name("backend") + " local");
  if (p.plant.delay_s > 0.0 && !p.plant.model)
    return Status::InvalidInput(name("monte_carlo") + " with " + name("delay") +
                                " is not supported yet (its draws are undelayed plants)");
  if (p.plant.nonlinear)
    return Status::InvalidInput(name("monte_carlo") + " draws linear plants: it does not take " +
                                name("plant") + " " + Quote(p.plant.name));
  return Status::Ok();
}

// The loop of `s` for `plant`: the one place a plant meets its loop (its dead
// time needs the sampled loop and a bounded delay line at its dt).
bool BuildLoopFor(const Plant& plant, const spec::LoopSpec& s, NameStyle style, evaluation::LoopOptions* loop,
                  std::string* error) {
  return BuildLoopOptions(s, style, loop, error) && CheckPlantInLoop(plant, *loop, style, error);
}

// With a runner (the trio), the sampled loop: a loop given otherwise is refused.
Status SampledForRunner(const BuildOptions& options, spec::LoopSpec* loop) {
  if (options.backend != Backend::kRunner) return Status::Ok();
  if (options.given.count("loop") > 0 && loop->loop != "sampled")
    return Status::InvalidInput(DisplayName("backend", options.style) + " lcm runs the sampled loop, not " +
                                DisplayName("loop", options.style) + " " + Quote(loop->loop));
  loop->loop = "sampled";
  return Status::Ok();
}

}  // namespace

Status BuildEvaluation(const spec::EvaluateSpec& s, const BuildOptions& options, EvaluationProblem* problem) {
  const NameStyle style = options.style;
  EvaluationProblem p;
  p.spec = s;
  p.spec.plant.Normalize();
  std::string error;
  if (!BuildPlant(p.spec.plant, style, &p.plant, &error) ||
      !BuildStepperParameters(p.spec.plant, style, &p.stepper, &error) ||
      !BuildMonteCarlo(p.spec, style, &p.monte_carlo, &error))
    return Status::InvalidInput(error);
  // The command line says where gains come from; a key names the list.
  if (p.spec.gains.empty() && style == NameStyle::kFlag)
    return Status::InvalidInput("--gains is required (or --spec FILE)");
  if (!BuildGains(p.spec.gains, style, &p.gains, &error)) return Status::InvalidInput(error);
  if (Status sampled = SampledForRunner(options, &p.spec.loop); !sampled.ok()) return sampled;
  p.time_scale = ResolveGainsTimeScale(p.spec.plant, p.plant, {p.gains}, options.given,
                                       TimeScaleScope::kNotPaper, &p.spec.loop);
  if (!BuildLoopFor(p.plant, p.spec.loop, style, &p.loop, &error) ||
      !BuildBounds(p.spec.bounds, style, &p.bounds, &error))
    return Status::InvalidInput(error);
  if (Status mc = CheckMonteCarlo(p, options); !mc.ok()) return mc;
  *problem = std::move(p);
  return Status::Ok();
}

Status RunEvaluation(const EvaluationProblem& problem, const EvaluationRunOptions& options,
                     EvaluationResult* result) {
  EvaluationResult r;
  const Status evaluated = evaluation::Evaluate(problem.plant, problem.gains, problem.loop, options.what,
                                                &r.evaluation, options.runner);
  if (!evaluated.ok()) return evaluated;
  const Status analysed = analysis::AnalyzeLoop(problem.plant, problem.gains, problem.loop,
                                                analysis::LoopAnalysisOptions{}, &r.analysis);
  if (!analysed.ok()) return analysed;
  if (problem.HasMonteCarlo() && options.monte_carlo) {
    const StepperMotorParameters* motor = problem.plant.name == "stepper_motor" ? &problem.stepper : nullptr;
    const Status drawn =
        analysis::RunMonteCarlo(problem.plant, motor, problem.gains, problem.loop, problem.monte_carlo,
                                &r.monte_carlo, options.monte_carlo_progress);
    if (!drawn.ok()) return drawn;
    r.monte_carlo_ran = true;
  }
  *result = std::move(r);
  return Status::Ok();
}

Status BuildPlantInLoop(const spec::PlantSpec& plant, const spec::LoopSpec& loop, NameStyle style, Plant* p,
                        evaluation::LoopOptions* options) {
  std::string error;
  Plant built;
  evaluation::LoopOptions l;
  if (!BuildPlant(plant, style, &built, &error) || !BuildLoopFor(built, loop, style, &l, &error))
    return Status::InvalidInput(error);
  *p = std::move(built);
  *options = l;
  return Status::Ok();
}

Status BuildFigureLoop(const spec::PlantSpec& plant, const spec::LoopSpec& loop,
                       const std::vector<PidGains>& gains, const std::set<std::string>& given,
                       NameStyle style, Plant* p, evaluation::LoopOptions* options) {
  Plant built;
  evaluation::LoopOptions unframed;
  // The plant, in its loop on the sampled grid (a dt that eq. (4)'s spacing
  // is no multiple of builds, as evaluate builds it); a given horizon or
  // sample time is checked as given when the framed loop builds.
  spec::LoopSpec gridded = loop;
  if (gridded.loop == "sampled") OnSampledGrid(gridded.dt_s, &gridded.sample_time_s, &gridded.horizon_s);
  if (Status st = BuildPlantInLoop(plant, gridded, style, &built, &unframed); !st.ok()) return st;
  spec::LoopSpec framed = loop;
  ResolveGainsTimeScale(plant, built, gains, given, TimeScaleScope::kFigure, &framed);
  return BuildPlantInLoop(plant, framed, style, p, options);
}

Status BuildController(const spec::EvaluateSpec& s, NameStyle style, PidGains* gains,
                       evaluation::LoopOptions* loop) {
  std::string error;
  PidGains g;
  evaluation::LoopOptions l;
  // The controller does not sample the response: on the sampled loop the
  // evaluation's grid is made a multiple of dt, so that a dt the default
  // spacing is no multiple of (1 s against eq. (4)'s 0.05 s) builds.
  spec::LoopSpec loop_spec = s.loop;
  if (loop_spec.loop == "sampled")
    OnSampledGrid(loop_spec.dt_s, &loop_spec.sample_time_s, &loop_spec.horizon_s);
  if (!BuildGains(s.gains, style, &g, &error) || !BuildLoopOptions(loop_spec, style, &l, &error))
    return Status::InvalidInput(error);
  *gains = g;
  *loop = l;
  return Status::Ok();
}

namespace {

// The pole of largest modulus, as text: "z = a+bj (|z| = m)".
std::string LargestPole(const evaluation::Stability& stability, double* modulus) {
  std::complex<double> largest = 0.0;
  for (const std::complex<double>& p : stability.poles)
    if (std::abs(p) > std::abs(largest)) largest = p;
  *modulus = std::abs(largest);
  std::ostringstream os;
  os << "z = " << spec::FormatNumber(largest.real());
  if (largest.imag() != 0.0)
    os << (largest.imag() < 0.0 ? "-" : "+") << spec::FormatNumber(std::abs(largest.imag())) << "j";
  os << " (|z| = " << spec::FormatNumber(*modulus) << ")";
  return os.str();
}

}  // namespace

Status CheckSampledController(const spec::EvaluateSpec& s, NameStyle style, SampledControllerCheck* check) {
  *check = SampledControllerCheck();
  spec::EvaluateSpec e = s;
  e.plant.Normalize();
  if (e.plant.plant.empty()) {
    check->verdict = "not checked (no plant given)";
    return Status::Ok();
  }
  e.loop.loop = "sampled";
  e.monte_carlo = 0;
  EvaluationProblem problem;
  BuildOptions build;
  build.style = style;
  if (Status built = BuildEvaluation(e, build, &problem); !built.ok()) return built;
  if (problem.plant.nonlinear) {
    check->verdict = "not checked (the nonlinear plant " + problem.plant.name +
                     " has no closed-loop poles: run pidlab evaluate --loop sampled at this dt)";
    return Status::Ok();
  }
  evaluation::EvaluateOptions what;
  what.compute_step_info = false;
  what.compute_iae_continuous = false;
  evaluation::Evaluation ev;
  if (Status run = evaluation::Evaluate(problem.plant, problem.gains, problem.loop, what, &ev); !run.ok())
    return run;
  double modulus = 0.0;
  const std::string pole = LargestPole(ev.stability, &modulus);
  const std::string plant = "the sampled loop of plant " + problem.spec.plant.plant;
  check->checked = true;
  check->stable = ev.stability.stable;
  check->verdict = check->stable ? plant + " is stable, largest pole " + pole
                                 : DisplayName("dt", style) + " " + spec::FormatNumber(problem.loop.dt_s) +
                                       " s: " + plant + " under these gains is unstable, pole " + pole +
                                       ": choose a smaller " + DisplayName("dt", style) + ", or give " +
                                       DisplayName("force", style) + " to write it anyway";
  return Status::Ok();
}

Status BuildNonlinearStepper(const spec::PlantSpec& s, NameStyle style, NonlinearStepperOptions* out) {
  std::string error;
  return Checked(BuildNonlinearOptions(s, style, out, &error), error);
}

bool IsPaperPlant(const spec::PlantSpec& p) {
  for (const std::string& name : BuiltinPlantNames())
    if (p.plant == name) return true;
  return false;
}

namespace {

// The design's closed loop (or the plant's own times) as a time scale, its
// spacing a multiple of dt on the sampled loop.
TimeScale DerivedTimeScale(const spec::TuningSpec& s, const Plant& plant) {
  double fastest = 0.0, slowest = 0.0;
  PlantTimes(plant, &fastest, &slowest);
  MigoOptions o;
  o.ms = s.tune.robustness > 1.0 && s.tune.robustness <= 4.0 ? s.tune.robustness : kMigoDefaultMs;
  o.response_time_s = s.tune.response_time_s > 0.0 ? s.tune.response_time_s : 0.0;
  if (s.tune.crossover_rad_s > 0.0 && std::isfinite(s.tune.crossover_rad_s))
    o.response_time_s = 2.0 / s.tune.crossover_rad_s;
  MigoDesign design;
  analysis::LoopAnalysis a;
  std::string from = "the plant's own time constants";
  const auto closed = [&](const PidGains& gains, double crossover_rad_s, const char* what) {
    evaluation::LoopOptions loop;
    if (!analysis::AnalyzeLoop(plant, gains, loop, analysis::LoopAnalysisOptions{}, &a).ok() || !a.stable ||
        !std::isfinite(a.slowest_time_constant_s) || !(crossover_rad_s > 0.0))
      return false;
    slowest = a.slowest_time_constant_s;
    fastest = std::min(fastest, 1.0 / crossover_rad_s);
    from = what;
    return true;
  };
  bool found = !plant.nonlinear && DesignMigo(plant, o, &design).ok() &&
               closed(design.gains, design.crossover_rad_s, "the migo design's closed loop");
  // Where migo finds none (1/(s^2 (0.005 s + 1)): no ultimate gain to start
  // from), the design engine's own closed loop, as the default tune designs
  // it: the plant's times alone can be shorter than its slowest mode.
  if (!found && !plant.nonlinear && s.tune.method == "optimal") {
    DesignOptions d;
    d.max_ms = o.ms;
    d.max_noise_gain = s.bounds.max_noise_gain;
    d.crossover_rad_s = s.tune.crossover_rad_s > 0.0 ? s.tune.crossover_rad_s
                        : o.response_time_s > 0.0    ? 2.0 / o.response_time_s
                                                     : 0.0;
    DesignSummary engine;
    found = DesignOptimal(plant, d, &engine).ok() &&
            closed(engine.gains, engine.crossover_rad_s, "the design engine's closed loop");
  }
  TimeScale t = LoopTimeScale(fastest, slowest, plant.delay_s);
  if (s.loop.loop == "sampled") OnSampledGrid(s.loop.dt_s, &t.sample_time_s, &t.horizon_s);
  t.reason = from + ": " + t.reason;
  return t;
}

// migo's default bound: SIMC's (tau_c = L) Ms on the plant, with the
// derivative filter migo uses, clamped to [kMigoMinDefaultMs,
// kMigoMaxDefaultMs]; kMigoMaxDefaultMs where SIMC does not apply.
double DefaultRobustness(const Plant& given, std::string* why) {
  // A reverse-acting plant's as -G's (the design engine designs it so).
  Plant plant = given;
  if (plant.tf.DcGain() < 0.0)
    for (double& n : plant.tf.num) n = -n;
  TuningRuleResult simc;
  analysis::LoopAnalysis a;
  evaluation::LoopOptions loop;
  loop.derivative_filter_ratio = kMigoFilterRatio;
  if (plant.nonlinear || !ApplyTuningRule(plant, TuningRule::kSimc, RuleForm::kPid, &simc).ok() ||
      !analysis::AnalyzeLoop(plant, simc.gains, loop, analysis::LoopAnalysisOptions{}, &a).ok() ||
      !a.stable || !std::isfinite(a.ms)) {
    *why = "at most " + spec::FormatNumber(kMigoMaxDefaultMs) + " (SIMC does not apply to this plant)";
    return kMigoMaxDefaultMs;
  }
  const double ms = std::clamp(a.ms, kMigoMinDefaultMs, kMigoMaxDefaultMs);
  *why = "SIMC's (tau_c = L) Ms on this plant, " + spec::FormatNumber(a.ms) + ", within [" +
         spec::FormatNumber(kMigoMinDefaultMs) + ", " + spec::FormatNumber(kMigoMaxDefaultMs) + "]";
  return ms;
}

// The bounds the design engine takes itself (max_ms as its --robustness).
bool EngineTakes(const std::string& key) {
  return key == "max_ms" || key == "max_mt" || key == "max_noise_gain" || key == "max_overshoot";
}

// A spec that says how to search (a field tagged kSearch other than the
// bounds the engine takes: an objective, a box, budgets, a margin, a
// settling or time-constant bound, the robust preset or set), or runs the
// sampled loop (on the caller's runner the trio's episodes are the point;
// in process the engine designs it when asked, --method optimal), asks for
// the search, not for the design engine. Returns why ("" for no):
// the flag or key that asked, as `given` names it.
std::string AsksForASearch(const spec::TuningSpec& s, const std::set<std::string>& given, bool runner) {
  static const std::vector<spec::FieldEntry> fields = spec::Fields<spec::TuningSpec>();
  for (const spec::FieldEntry& e : fields)
    if (e.field.Has(spec::kSearch) && given.count(e.field.key) > 0 && !EngineTakes(e.field.key))
      return e.field.key;
  if (s.loop.loop == "sampled" && runner) return "backend";
  return "";
}

// The engine's noise bound: DefaultNoiseGain, unless given (inf: none).
void ResolveNoiseGain(spec::TuningSpec* s, const std::set<std::string>& given, TimeScale* t) {
  Plant plant;
  if (given.count("max_noise_gain") > 0 || !BuildPlant(s->plant, NameStyle::kKey, &plant, nullptr)) {
    t->noise_gain_reason = "given";
    return;
  }
  s->bounds.max_noise_gain = DefaultNoiseGain(plant, &t->noise_gain_reason);
}

// The method, and why (t->method_reason): the design engine unless one is
// given, the plant is the nonlinear stepper, or a flag asks for a search.
void ResolveMethod(spec::TuningSpec* s, const std::set<std::string>& given, bool runner, TimeScale* t) {
  const auto kept = [&given](const char* key) { return given.count(key) > 0; };
  const std::string search = AsksForASearch(*s, given, runner);
  if (kept("method")) {
    t->method_reason = "given";
  } else if (s->plant.plant == "stepper_nonlinear") {
    t->method_reason = "the nonlinear stepper is tuned by the search on the paper's objective";
  } else if (!search.empty()) {
    t->method_reason =
        search == "backend"
            ? "the trio's episodes tune the sampled loop: the search on the paper's objective"
            : "'" + search +
                  "' asks for the search on the paper's objective (the design engine takes --robustness, "
                  "--max-ms, --max-mt, --max-noise-gain and --max-overshoot)";
  } else {
    s->tune.method = "optimal";
    t->method_reason =
        s->loop.loop == "sampled"
            ? "the default: the design engine, on the sampled loop (the ZOH plant and the discrete PID)"
            : "the default: the design engine";
  }
  // The engine's Ms bound from --max-ms where --robustness is not given.
  if (s->tune.method == "optimal" && kept("max_ms") && !kept("robustness") && std::isfinite(s->bounds.max_ms))
    s->tune.robustness = s->bounds.max_ms;
}

// A filtered derivative (tf = kd / (10 kp)) unless one is given: off the
// paper's plants for every method (an ideal derivative has an unbounded
// noise gain, and on relative degree 1 with dead time a neutral loop); on
// them for migo, which designs with it. The rules' PI has no derivative,
// and the design engine designs its own filter (N = Td / tf searched).
void ResolveFilter(spec::TuningSpec* s, const std::set<std::string>& given, bool paper) {
  const auto kept = [&given](const char* key) { return given.count(key) > 0; };
  if (kept("derivative_filter") || kept("derivative_filter_ratio")) return;
  if (s->tune.method == "optimal") {
    s->loop.derivative_filter_s = 0.0;
    s->loop.derivative_filter_ratio = 0.0;
    return;
  }
  const bool pi_rule = s->tune.rule == "pi" &&
                       (s->tune.method == "migo" || s->tune.method == "simc" || s->tune.method == "amigo");
  if (!pi_rule && !kept("robust") && (!paper || s->tune.method == "migo")) {
    s->loop.derivative_filter_s = 0.0;
    s->loop.derivative_filter_ratio = kMigoFilterRatio;
  }
}

// The reasons a time scale carries besides its own.
struct Reasons {
  std::string robustness, noise_gain, method;
  explicit Reasons(const TimeScale& t)
      : robustness(t.robustness_reason), noise_gain(t.noise_gain_reason), method(t.method_reason) {}
  TimeScale Into(TimeScale t) const {
    t.robustness_reason = robustness;
    t.noise_gain_reason = noise_gain;
    t.method_reason = method;
    return t;
  }
};

// Method, filter and time scale from the plant.
TimeScale ResolvePlantDefaults(spec::TuningSpec* s, const std::set<std::string>& given, bool runner) {
  const auto kept = [&given](const char* key) { return given.count(key) > 0; };
  TimeScale t;
  t.horizon_s = s->loop.horizon_s;
  t.sample_time_s = s->loop.sample_time_s;
  const bool paper = IsPaperPlant(s->plant);
  const bool timed = kept("horizon") || kept("sample_time");
  ResolveMethod(s, given, runner, &t);
  ResolveFilter(s, given, paper);
  const bool optimal = s->tune.method == "optimal";
  if (paper) {
    if (optimal) ResolveNoiseGain(s, given, &t);
    // Given as eq. (4) has them (a result's echo): eq. (4) still.
    const spec::LoopSpec defaults;
    const bool eq4 =
        s->loop.horizon_s == defaults.horizon_s && s->loop.sample_time_s == defaults.sample_time_s;
    t.source = eq4 ? "eq. (4)" : "given";
    t.reason = eq4 ? "the paper's eq. (4): n = 25 s, ts = 0.05 s" : "given";
    t.robustness_reason =
        kept("robustness") ? "given" : "the default, " + spec::FormatNumber(s->tune.robustness);
    return t;
  }
  Plant plant;
  std::string error;
  if (!BuildPlant(s->plant, NameStyle::kKey, &plant, &error)) {
    if (timed) t.source = t.reason = "given";
    return t;
  }
  if ((s->tune.method == "migo" || optimal) && !kept("robustness") && !kept("max_ms")) {
    s->tune.robustness = DefaultRobustness(plant, &t.robustness_reason);
  } else {
    t.robustness_reason = "given";
  }
  if (optimal) ResolveNoiseGain(s, given, &t);
  const Reasons reasons(t);
  // (The robust preset's bound on the slowest time constant is a tenth of
  // this horizon: at least the migo design's own.)
  const TimeScale derived = DerivedTimeScale(*s, plant);
  if (timed) {
    // Given as the plant gives them (a result's echo): the plant's still.
    const bool same =
        s->loop.horizon_s == derived.horizon_s && s->loop.sample_time_s == derived.sample_time_s;
    if (!same) t.source = t.reason = "given";
    return same ? reasons.Into(derived) : t;
  }
  s->loop.horizon_s = derived.horizon_s;
  s->loop.sample_time_s = derived.sample_time_s;
  return reasons.Into(derived);
}

}  // namespace

SearchBox ResolveTuningSpec(spec::TuningSpec* s, const std::set<std::string>& given, TimeScale* time_scale,
                            Backend backend) {
  const TimeScale t = ResolvePlantDefaults(s, given, backend == Backend::kRunner);
  if (time_scale) *time_scale = t;
  ResolveRobustPreset(s, given);
  return ResolveSearchBox(s, given);
}

Status BuildTuning(const spec::TuningSpec& s, const BuildOptions& options, TuningProblem* problem) {
  const auto name = [&options](const char* key) { return DisplayName(key, options.style); };
  TuningProblem p;
  p.spec = s;
  p.spec.plant.Normalize();
  p.box = ResolveTuningSpec(&p.spec, options.given, &p.time_scale, options.backend);
  std::string error;
  if (!BuildPlant(p.spec.plant, options.style, &p.plant, &error) ||
      !BuildTuneOptions(p.spec, options.style, &p.options, &error) ||
      !BuildLoopFor(p.plant, p.spec.loop, options.style, &p.options.loop, &error))
    return Status::InvalidInput(error);
  p.options.robustness_given = options.given.count("robustness") > 0;
  const bool sampled = p.options.loop.loop == evaluation::LoopKind::kSampled;
  if (p.plant.nonlinear && !sampled)
    return Status::InvalidInput(
        name("plant") + " " + p.plant.name + " is nonlinear: tune it on the sampled loop (" + name("loop") +
        " sampled" + (options.style == NameStyle::kFlag ? " " + name("dt") + " 1e-4" : std::string()) + ")");
  if (options.backend == Backend::kRunner && !sampled)
    return Status::InvalidInput(name("backend") + " lcm runs the sampled loop: add " + name("loop") +
                                " sampled");
  *problem = std::move(p);
  return Status::Ok();
}

namespace {

bool AtAnUpperEdge(const TuneSummary& s) {
  for (const std::string& b : s.at_bounds)
    if (b.size() > 3 && b.compare(b.size() - 3, 3, "_hi") == 0) return true;
  return false;
}

}  // namespace

Status RunTuning(const TuningProblem& problem, const TuningRunOptions& options, TuningResult* result) {
  TuningResult r;
  TuneOptions o = problem.options;
  if (options.parallel_for) o.parallel_for = options.parallel_for;
  Status tuned = Tune(problem.plant, o, &r.summary, options.progress, options.runner);
  // A PID that cannot be evaluated (an ideal derivative on relative degree 1
  // with dead time: every loop neutral) gets the best filtered PID instead.
  if (tuned.ok() && !r.summary.stable && !IsTuningRule(o.method) && o.method != TuneMethod::kMigo &&
      IdealDerivativeMakesLoopNeutral(problem.plant, o)) {
    o.loop.pid.derivative_filter_s = 0.0;
    o.loop.derivative_filter_ratio = kMigoFilterRatio;
    r.fallback =
        "an ideal derivative makes every loop on this plant neutral (relative degree 1 with dead "
        "time): tuned the best filtered PID instead, tf = Td / " +
        spec::FormatNumber(kMigoFilterRatio) + " (--derivative-filter-ratio " +
        spec::FormatNumber(kMigoFilterRatio) + ")";
    tuned = Tune(problem.plant, o, &r.summary, options.progress, options.runner);
  }
  // An optimum on the edge of a box nobody gave is the box's, not the
  // plant's: tenfold wider, at most twice (in process; over the trio, and on
  // the paper's plants, whose box is the paper's, the edge is reported).
  while (tuned.ok() && r.summary.stable && problem.box.source != "given" &&
         !IsPaperPlant(problem.spec.plant) && !IsTuningRule(o.method) && !options.runner &&
         AtAnUpperEdge(r.summary) && r.widened_from.size() < 2 && o.upper < kMaxGain) {
    r.widened_from.push_back(o.upper);
    o.upper = std::min(10.0 * o.upper, kMaxGain);
    tuned = Tune(problem.plant, o, &r.summary, options.progress, options.runner);
  }
  r.box_upper = o.upper;
  r.options = o;
  if (tuned.ok() && r.summary.stable) {
    // With two_dof, the loop with the setpoint weights found.
    r.loop = WithSetpointWeights(o.loop, r.summary.two_dof);
    const Status evaluated = evaluation::Evaluate(problem.plant, r.summary.gains, r.loop,
                                                  evaluation::EvaluateOptions{}, &r.evaluation);
    if (!evaluated.ok()) return evaluated;
    const Status analysed = analysis::AnalyzeLoop(problem.plant, r.summary.gains, r.loop,
                                                  analysis::LoopAnalysisOptions{}, &r.analysis);
    if (!analysed.ok()) return analysed;
  }
  *result = std::move(r);
  return tuned;
}

}  // namespace pidlab::tune
