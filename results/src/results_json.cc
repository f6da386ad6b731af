#include "pidlab/results/results_json.h"

#include <cmath>

using pidlab::analysis::Cancellation;
using pidlab::analysis::Distribution;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopBounds;
using pidlab::analysis::LoopBoundsViolations;
using pidlab::analysis::MonteCarloOptions;
using pidlab::analysis::MonteCarloSummary;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::ObjectiveKind;
using pidlab::tune::ProcessModel;
using pidlab::tune::TuneMethod;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;
using pidlab::tune::TuningRuleResult;

namespace pidlab::results {

nlohmann::json JsonNumber(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json ToJson(const PidGains& g) { return {{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}, {"tf", g.tf}}; }

namespace {

// The stepper_nonlinear verdict and peaks (docs/stepper.md): "status" and "motor".
void AddMotor(const Evaluation& ev, nlohmann::json* j) {
  if (!ev.has_motor) return;
  (*j)["status"] = ev.lost_steps ? "lost_steps" : "ok";
  (*j)["motor"] = {{"lost_steps", ev.lost_steps},
                   {"final_error_rad", JsonNumber(ev.final_error)},
                   {"peak_phase_voltage_v", JsonNumber(ev.motor.phase_voltage_v)},
                   {"peak_phase_current_a", JsonNumber(ev.motor.phase_current_a)},
                   {"peak_load_angle_rad", JsonNumber(ev.motor.load_angle_rad)}};
  if (!ev.motor_note.empty()) (*j)["motor"]["note"] = ev.motor_note;
}

// simc, amigo: the model the rule used ("model") and its controller
// ("tuning_rule"). The gains are scored on the spec's loop with the plant as
// given: "delay_simulated" is true when the plant has a dead time (only the
// sampled loop takes one), false when the model's delay is the half rule's alone.
void AddTuningRule(const TuneOptions& o, const TuningRuleResult& r, nlohmann::json* j) {
  const ProcessModel& m = r.model;
  (*j)["model"] = {{"kind", ToString(m.kind)},
                   {"gain", m.gain},
                   {"time_constants", m.time_constants},
                   {"delay", m.delay_s},
                   {"half_rule", m.half_rule}};
  (*j)["tuning_rule"] = {{"rule", ToString(r.form)},
                         {"kc", r.kc},
                         {"ti_s", r.ti_s},
                         {"td_s", r.td_s},
                         {"controller_form", r.controller_form},
                         {"evaluated_on", ToString(o.loop.loop)},
                         {"delay_simulated", r.plant_delay_s > 0.0},
                         {"message", r.message}};
}

}  // namespace

nlohmann::json ToJson(const Evaluation& ev) {
  nlohmann::json poles = nlohmann::json::array();
  for (const auto& p : ev.stability.poles) poles.push_back({{"re", p.real()}, {"im", p.imag()}});
  nlohmann::json j;
  j["plant"] = ev.plant.name;
  j["plant_tf"] = {{"num", ev.plant.tf.num}, {"den", ev.plant.tf.den}};
  j["gains"] = ToJson(ev.gains);
  j["loop"] = ToString(ev.options.loop);
  if (ev.options.loop == LoopKind::kSampled) j["dt_s"] = ev.options.dt_s;
  j["reference"] = ev.options.reference;
  j["sample_time_s"] = ev.options.sample_time_s;
  j["horizon_s"] = ev.options.horizon_s;
  j["samples"] = ev.options.NumSamples();
  j["disturbance"] = {{"kind", ToString(ev.options.disturbance.kind)},
                      {"amplitude", ev.options.disturbance.amplitude},
                      {"period_s", ev.options.disturbance.period_s}};
  j["stable"] = ev.stability.stable;
  j["closed_loop_poles"] = poles;
  j["pole_domain"] = ev.options.loop == LoopKind::kSampled ? "z" : "s";
  j["iae"] = JsonNumber(ev.iae);
  j["iae_per_unit"] = JsonNumber(ev.iae_per_unit);
  j["iae_undisturbed"] = JsonNumber(ev.iae_undisturbed);
  j["load_iae"] = JsonNumber(ev.load_iae);
  j["load_iae_continuous"] = JsonNumber(ev.load_iae_continuous);
  j["ise"] = JsonNumber(ev.ise);
  j["itae"] = JsonNumber(ev.itae);
  j["iae_continuous"] = JsonNumber(ev.iae_continuous);
  const bool v = ev.step.valid;
  j["rise_time_s"] = v ? JsonNumber(ev.step.rise_time_s) : nlohmann::json(nullptr);
  j["overshoot_pct"] = v ? JsonNumber(ev.step.overshoot_pct) : nlohmann::json(nullptr);
  j["settling_time_s"] = v ? JsonNumber(ev.step.settling_time_s) : nlohmann::json(nullptr);
  j["peak"] = v ? JsonNumber(ev.step.peak) : nlohmann::json(nullptr);
  j["peak_time_s"] = v ? JsonNumber(ev.step.peak_time_s) : nlohmann::json(nullptr);
  j["final_value"] = v ? JsonNumber(ev.step.final_value) : nlohmann::json(nullptr);
  if (!ev.step.note.empty()) j["step_info_note"] = ev.step.note;
  AddMotor(ev, &j);
  return j;
}

namespace {

nlohmann::json TwoDofResponseJson(const tune::TwoDofResponse& r) {
  return {{"setpoint_weights", {r.b, r.c}},
          {"setpoint",
           {{"iae", JsonNumber(r.setpoint_iae)},
            {"overshoot_pct", JsonNumber(r.overshoot_pct)},
            {"rise_time_s", JsonNumber(r.rise_time_s)},
            {"settling_time_s", JsonNumber(r.settling_time_s)}}},
          {"load", {{"iae", JsonNumber(r.load_iae)}}},
          {"ms", JsonNumber(r.ms)}};
}

}  // namespace

nlohmann::json TwoDofJson(const tune::TwoDofSummary& s) {
  if (!s.ran) return {{"ran", false}, {"message", s.message}};
  return {{"ran", true},
          {"setpoint_weights", {s.b, s.c}},
          {"setpoint_filter_s", JsonNumber(s.setpoint_filter_s)},
          {"before", TwoDofResponseJson(s.before)},
          {"after", TwoDofResponseJson(s.after)},
          {"evaluations", s.evaluations},
          {"termination", optim::ToString(s.termination)},
          {"message", s.message}};
}

namespace {

// TuneJson's "design" (the engine, its bounds and what was active) and
// response_time_s (the knob's).
void AddDesign(const tune::DesignSummary& d, nlohmann::json* j) {
  (*j)["design"] = {
      {"engine", "optimal"},
      {"objective", "load integral |e| dt (unit step at the plant input, r = 0)"},
      {"load_iae", JsonNumber(d.load_iae)},
      {"setpoint_iae", JsonNumber(d.setpoint_iae)},
      {"ms_bound", JsonNumber(d.ms_bound)},
      {"mt_bound", JsonNumber(d.mt_bound)},
      {"noise_gain_bound", JsonNumber(d.noise_gain_bound)},
      {"td_bound_s", JsonNumber(d.td_bound_s)},
      {"ms", JsonNumber(d.ms)},
      {"mt", JsonNumber(d.mt)},
      {"noise_gain", JsonNumber(d.noise_gain)},
      {"crossover_rad_s", JsonNumber(d.crossover_rad_s)},
      {"phase_margin_deg", JsonNumber(d.phase_margin_deg)},
      {"active", d.active},
      {"unconstrained",
       {{"load_iae", JsonNumber(d.unconstrained_load_iae)},
        {"gap_pct", JsonNumber(d.unconstrained_gap_pct)},
        {"dropped", d.dropped},
        {"note", d.unconstrained_note}}},
      {"overshoot_pct", JsonNumber(d.overshoot_pct)},
      {"overshoot_unit_weights_pct", JsonNumber(d.overshoot_unit_weights_pct)},
      {"overshoot_met", d.overshoot_met},
      {"overshoot_target_pct", JsonNumber(d.overshoot_target_pct)},
      {"overshoot_cap_note", d.overshoot_cap_note},
      {"setpoint_filter_s", JsonNumber(d.setpoint_filter_s)},
      {"setpoint_note", d.setpoint_note},
      {"front_note", d.front_note},
      {"reverse_acting", d.reverse_acting},
      {"reverse_note", d.reverse_acting ? "the loop acts in reverse: the plant's gain is negative, "
                                          "so are kp, ki and kd (u = kp e + ...)"
                                        : ""},
      {"evaluations", d.evaluations},
      {"message", d.message}};
  (*j)["response_time_s"] = JsonNumber(d.response_time_s);
}

// TuneJson's "refine": the Ceres cross-check.
nlohmann::json RefineJson(const TuneOptions& o, const TuneSummary& s) {
  return {{"ran", s.refine.ran},
          {"gains", ToJson(s.refine.gains)},
          {"objective", JsonNumber(s.refine.objective)},
          {"iae", JsonNumber(o.objective == ObjectiveKind::kIae ? s.refine.objective : NAN)},
          {"verdict", ToString(s.refine.verdict, s.method)},
          {"termination", ToString(s.refine.termination)},
          {"iterations", s.refine.iterations},
          {"relative_improvement", JsonNumber(s.refine.relative_improvement)},
          {"runs", s.refine.runs},
          {"start_index", s.refine.start_index},
          {"message", s.refine.message}};
}

// TuneJson's "constraints": the bounds the search obeyed, and the filter.
nlohmann::json ConstraintsJson(const TuneOptions& o) {
  const LoopBounds& b = o.bounds;
  return {{"max_ms", JsonNumber(b.max_ms)},
          {"max_mt", JsonNumber(b.max_mt)},
          {"max_noise_gain", JsonNumber(b.max_noise_gain)},
          {"min_phase_margin_deg", b.min_phase_margin_deg},
          {"min_gain_margin", b.min_gain_margin},
          {"max_time_constant_s", JsonNumber(b.max_time_constant_s)},
          {"max_overshoot_pct", JsonNumber(o.max_overshoot_pct)},
          {"max_settling_time_s", JsonNumber(o.max_settling_time_s)},
          {"derivative_filter_s", o.loop.pid.derivative_filter_s},
          {"derivative_filter_ratio", o.loop.derivative_filter_ratio}};
}

// TuneJson's "robust_set" (robust_samples > 0).
nlohmann::json RobustSetJson(const TuneOptions& o, const TuneSummary& s) {
  return {{"samples", o.robust_samples},
          // null where the draws come from a model's covariance (no spread)
          {"spread", s.robust_perturbed == analysis::kCovariancePerturbed ? nlohmann::json(nullptr)
                                                                          : nlohmann::json(o.robust_spread)},
          {"quantile", o.robust_quantile},
          {"size", s.robust_set_size},
          {"invalid_draws", s.robust_invalid_draws},
          {"redrawn", s.robust_redrawn},
          {"perturbed", s.robust_perturbed},
          {"nominal_objective", JsonNumber(s.nominal_objective)}};
}

}  // namespace

nlohmann::json TuneJson(const Plant& p, const TuneOptions& o, const TuneSummary& s, const Evaluation& ev,
                        const std::string& backend) {
  nlohmann::json j;
  j["plant"] = p.name;
  j["method"] = ToString(o.method);
  j["objective_kind"] = ToString(o.objective);
  if (o.objective == ObjectiveKind::kSetpointLoad) j["load_weight"] = o.load_weight;
  j["load_iae"] = s.stable ? JsonNumber(ev.load_iae) : nlohmann::json(nullptr);
  j["backend"] = backend;
  j["loop"] = ToString(o.loop.loop);
  j["gains"] = ToJson(s.gains);
  j["objective"] = JsonNumber(s.objective);
  j["reference"] = o.loop.reference;
  j["iae"] = s.stable ? JsonNumber(ev.iae) : nlohmann::json(nullptr);
  j["iae_per_unit"] = s.stable ? JsonNumber(ev.iae_per_unit) : nlohmann::json(nullptr);
  j["stable"] = s.stable && ev.stability.stable;
  j["closed_loop_poles"] = s.stable ? ToJson(ev)["closed_loop_poles"] : nlohmann::json::array();
  j["rise_time_s"] = s.stable ? ToJson(ev)["rise_time_s"] : nlohmann::json(nullptr);
  j["overshoot_pct"] = s.stable ? ToJson(ev)["overshoot_pct"] : nlohmann::json(nullptr);
  j["settling_time_s"] = s.stable ? ToJson(ev)["settling_time_s"] : nlohmann::json(nullptr);
  j["search"] = {{"gains", ToJson(s.search_gains)},
                 {"objective", JsonNumber(s.search_objective)},
                 {"termination", ToString(s.optimizer.termination)},
                 {"starts", s.optimizer.starts},
                 {"message", s.optimizer.message}};
  j["box"] = {{"lower", o.lower}, {"upper", o.upper}};
  j["at_bounds"] = s.at_bounds;
  j["evaluations"] = s.evaluations;
  j["rejected_evaluations"] = s.optimizer.rejected_evaluations;
  j["iterations"] = s.iterations;
  j["seed"] = o.seed;
  j["wall_time_s"] = s.wall_time_s;
  j["refine"] = RefineJson(o, s);
  if (o.method == TuneMethod::kZieglerNichols)
    j["ziegler_nichols"] = {{"ultimate_gain", s.ziegler_nichols.ultimate_gain},
                            {"ultimate_period_s", s.ziegler_nichols.ultimate_period_s},
                            {"rule", ToString(o.zn_rule)}};
  if (o.method == TuneMethod::kSimc || o.method == TuneMethod::kAmigo) AddTuningRule(o, s.tuning_rule, &j);
  j["constraints"] = ConstraintsJson(o);
  if (o.robust_samples > 0) j["robust_set"] = RobustSetJson(o, s);
  if (s.stable) AddMotor(ev, &j);
  if (o.two_dof || s.two_dof.ran) j["two_dof"] = TwoDofJson(s.two_dof);
  if (o.method == TuneMethod::kOptimal) AddDesign(s.design, &j);
  if (o.method == TuneMethod::kMigo)
    j["migo"] = {{"robustness", o.robustness_ms},
                 {"phase_margin_deg", o.robustness_phase_margin_deg},
                 {"ms_bound", JsonNumber(s.migo.ms_bound)},
                 {"response_time_s", o.response_time_s},
                 {"ms", JsonNumber(s.migo.ms)},
                 {"mt", JsonNumber(s.migo.mt)},
                 {"crossover_rad_s", JsonNumber(s.migo.crossover_rad_s)},
                 {"setpoint_weight_b", s.migo.b},
                 {"setpoint_weight_c", s.migo.c},
                 {"message", s.migo.message}};
  return j;
}

nlohmann::json TimeScaleJson(const tune::TimeScale& t) {
  return {{"horizon_s", t.horizon_s},
          {"sample_time_s", t.sample_time_s},
          {"source", t.source},
          {"reason", t.reason}};
}

nlohmann::json RobustnessJson(const LoopAnalysis& a, const LoopBounds& bounds) {
  auto complex_json = [](const std::complex<double>& c) {
    return nlohmann::json{{"re", c.real()}, {"im", c.imag()}};
  };
  nlohmann::json j;
  j["loop"] = ToString(a.loop);
  j["stable"] = a.stable;
  j["ms"] = JsonNumber(a.ms);
  j["mt"] = JsonNumber(a.mt);
  j["gain_margin"] = JsonNumber(a.gain_margin);
  j["phase_margin_deg"] = JsonNumber(a.phase_margin_deg);
  j["delay_margin_s"] = JsonNumber(a.delay_margin_s);
  j["noise_gain"] = JsonNumber(a.noise_gain);
  j["slowest_time_constant_s"] = JsonNumber(a.slowest_time_constant_s);
  j["ms_rad_s"] = JsonNumber(a.ms_rad_s);
  j["mt_rad_s"] = JsonNumber(a.mt_rad_s);
  j["noise_gain_rad_s"] = JsonNumber(a.noise_gain_rad_s);
  j["gain_crossover_rad_s"] = JsonNumber(a.gain_crossover_rad_s);
  j["phase_crossover_rad_s"] = JsonNumber(a.phase_crossover_rad_s);
  j["gain_crossovers_rad_s"] = a.gain_crossovers_rad_s;
  j["phase_crossovers_rad_s"] = a.phase_crossovers_rad_s;
  // Every crossover's own margin, in the order of the crossovers (allmargin).
  j["phase_margins_deg"] = a.phase_margins_deg;
  j["gain_margins"] = a.gain_margins;
  j["delay_s"] = a.delay_s;
  nlohmann::json cancellations = nlohmann::json::array();
  for (const Cancellation& c : a.cancellations)
    cancellations.push_back({{"pole", complex_json(c.pole)},
                             {"zero", complex_json(c.zero)},
                             {"relative_distance", c.relative_distance}});
  j["cancellations"] = cancellations;
  nlohmann::json notes = nlohmann::json::object();
  if (!a.gain_margin_note.empty()) notes["gain_margin"] = a.gain_margin_note;
  if (!a.phase_margin_note.empty()) notes["phase_margin_deg"] = notes["delay_margin_s"] = a.phase_margin_note;
  if (!a.noise_gain_note.empty()) notes["noise_gain"] = a.noise_gain_note;
  if (!a.time_constant_note.empty()) notes["slowest_time_constant_s"] = a.time_constant_note;
  if (!a.stability_note.empty()) notes["stable"] = a.stability_note;
  j["notes"] = notes;
  j["violations"] = LoopBoundsViolations(a, bounds);
  j["method"] = a.method;
  return j;
}

nlohmann::json LinearizeJson(const TransferFunction& linearisation, const TransferFunction& eq3,
                             double input_scale) {
  nlohmann::json j;
  j["plant"] = "stepper_nonlinear";
  j["num"] = linearisation.num;
  j["den"] = linearisation.den;
  j["eq3"] = {{"num", eq3.num}, {"den", eq3.den}};
  j["input_scale"] = input_scale;
  return j;
}

nlohmann::json DistributionJson(const Distribution& d) {
  return {{"count", d.count},
          {"min", JsonNumber(d.min)},
          {"median", JsonNumber(d.median)},
          {"p95", JsonNumber(d.p95)},
          {"max", JsonNumber(d.max)}};
}

nlohmann::json MonteCarloJson(const MonteCarloOptions& mc, const MonteCarloSummary& s) {
  return {{"samples", s.samples},
          {"spread", s.perturbed == analysis::kCovariancePerturbed ? nlohmann::json(nullptr)
                                                                   : nlohmann::json(mc.spread)},
          {"seed", mc.seed},
          {"perturbed", s.perturbed},
          {"stable", s.stable},
          {"invalid", s.invalid},
          {"redrawn", s.redrawn},
          {"stable_fraction", s.stable_fraction},
          {"iae", DistributionJson(s.iae)},
          {"overshoot_pct", DistributionJson(s.overshoot_pct)},
          {"ms", DistributionJson(s.ms)}};
}

}  // namespace pidlab::results
