#pragma once
// The one description of an evaluation and of a tuning (docs/spec.md).
//
// A spec is plain data, the values a user types, with its fields listed once
// in Serialize(Archive*). Every front end reads and writes it through that
// list: the flags of `pidlab evaluate`, `tune` and `plot` (tools/cli_spec.h),
// the keywords of pidlab.evaluate and pidlab.tune (tools/python/), the JSON
// form (`--spec FILE`, and the "spec" every --json result echoes; json.h),
// and the field-table test. What the values mean, and their validation, is
// one library function per job (tuner/tune/problem.h), which names a bad field
// as the front end does (NameStyle).
//
// Archive: any type with
//   template <typename T> void Visit(const Field& field, T* value);
// for T in double, std::uint64_t, int, bool, std::string,
// std::vector<double>, std::pair<double, double> (LO, HI) and
// std::map<std::string, double> (NAME=VALUE).

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/spec/field.h"

namespace pidlab::spec {

/// The version of the JSON form; a spec file names it as "version".
inline constexpr int kSpecVersion = 1;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
/// The multi-start's default design (kMultiStartDesignPoints, checked in tuner).
inline constexpr int kDefaultDesignPoints = 1024;

/// The plant G(s): a built-in by name, a custom num/den, an identified model
/// ("model:FILE", or `model` FILE), or the nonlinear stepper with its options.
struct PlantSpec {
  std::string plant;
  /// The file of an identified model (`pidlab identify --out`): the same as
  /// plant "model:FILE", which Normalize makes of it.
  std::string model;
  std::vector<double> num, den;
  std::map<std::string, double> stepper;  // Table I overrides, NAME -> value
  double detent_torque_nm = 0.0, load_torque_nm = 0.0, load_step_nm = 0.0, load_step_time_s = 0.0;
  double voltage_limit_v = kInf, input_scale = 0.0;
  std::string drive = "linear";
  double delay_s = 0.0;  // dead time L, s (docs/deadtime.md)

  /// A custom plant (num/den given) is named "custom", and a model given as
  /// `model` FILE is plant "model:FILE", however it was typed, so that a spec
  /// echoes one form. (A `model` next to another plant is left for
  /// BuildPlant to refuse.)
  void Normalize() {
    if (!model.empty() && (plant.empty() || plant == "model:" + model)) {
      plant = "model:" + model;
      model.clear();
    }
    if (plant.empty() && (!num.empty() || !den.empty())) plant = "custom";
  }

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(
        {"plant",
         "double_integrator (alias linear) = 1/s^2, oscillator (alias nonlinear) = 1/(s^2+1), stepper_motor "
         "(alias stepper) = eq. (3), stepper_nonlinear = the nonlinear PM stepper (sampled loop; "
         "docs/stepper.md), custom with --num/--den, or model:FILE, the model pidlab identify --out wrote "
         "(docs/identify.md)",
         "", kEpisode, R"("oscillator")"},
        &plant);
    a->Visit({"model",
              "the model file pidlab identify --out wrote as the plant, the same as --plant model:FILE; its "
              "draws (--monte-carlo, --robust-samples) come from the parameters' covariance",
              "", kNone, R"("model.json")"},
             &model);
    a->Visit({"num", "custom plant numerator, descending powers of s, e.g. 1", "", kEpisode, "[2]"}, &num);
    a->Visit(
        {"den", "custom plant denominator, descending powers of s, e.g. 1,0,0", "", kEpisode, "[1, 3, 1]"},
        &den);
    a->Visit({"delay", "dead time L of the plant, G(s) e^(-sL), s (docs/deadtime.md)", "s", kEpisode, "0.3"},
             &delay_s);
    a->Visit(
        {"stepper",
         "override a Table I parameter, NAME=VALUE (resistance_ohm, self_inductance_h, mutual_inductance_h, "
         "inertia_kg_m2, rotor_teeth, viscous_friction, tooth_pitch_rad, stationary_current_a, "
         "flux_linkage); repeatable",
         "", kEpisode, R"({"resistance_ohm": 5.5})"},
        &stepper);
    a->Visit({"detent_torque", "stepper_nonlinear: detent torque amplitude T_d (T_d sin(4 N_r theta))", "N m",
              kEpisode, "0.01"},
             &detent_torque_nm);
    a->Visit({"load_torque", "stepper_nonlinear: constant load torque", "N m", kEpisode, "0.02"},
             &load_torque_nm);
    a->Visit({"load_step", "stepper_nonlinear: a further load torque step at --load-step-time", "N m",
              kEpisode, "0.03"},
             &load_step_nm);
    a->Visit({"load_step_time", "stepper_nonlinear: time of the load step", "s", kEpisode, "0.01"},
             &load_step_time_s);
    a->Visit({"voltage_limit", "stepper_nonlinear: phase-voltage limit of the drive (default: none)", "V",
              kEpisode | kInfinite, "24"},
             &voltage_limit_v);
    a->Visit(
        {"input_scale",
         "stepper_nonlinear: g in phi = theta0 + g u; 0 (default) = (L-M)/L, which makes the linearisation "
         "eq. (3); 1 = the physical angle command",
         "", kEpisode, "1"},
        &input_scale);
    a->Visit(
        {"drive",
         "stepper_nonlinear: linear (phase voltages proportional to u, default) or microstep (sine table at "
         "phi = theta0 + g u, wraps every electrical period)",
         "", kEpisode, R"("microstep")"},
        &drive);
  }
};

/// The loop: kind, timing, reference, disturbance and the discrete PID's
/// options.
struct LoopSpec {
  std::string loop = "continuous";
  double dt_s = 1e-3, sample_time_s = 0.05, horizon_s = 25.0, reference = 1.0;
  /// Strict stability: 1e-9 to evaluate; the tuner accepts candidates only
  /// with 0.01 (ForTuning).
  double stability_margin = 1e-9;
  std::string disturbance;  // "": square if an amplitude is given, else none
  double disturbance_amplitude = 0.0, disturbance_period_s = 2.0, disturbance_phase_s = 0.0;
  double disturbance_step_time_s = 0.0, noise_hold_s = 0.01;
  std::uint64_t seed = 1;
  /// Chirp band F0,F1 in Hz ([0, 0]: not given) and duration T in s (0: the
  /// horizon).
  std::pair<double, double> chirp_band{0.0, 0.0};
  double chirp_duration_s = 0.0;
  /// Standard deviation of the seeded Gaussian noise on the measured y
  /// (sampled loop; 0 = none).
  double measurement_noise = 0.0;
  /// Resolution q of the measured y (a sensor's or an ADC's step; sampled
  /// loop; 0 = exact).
  double measurement_resolution = 0.0;
  double derivative_filter_s = 0.0, derivative_filter_ratio = 0.0;
  std::pair<double, double> output_limits{-kInf, kInf};
  std::string anti_windup = "clamping", derivative_on = "error", integral = "backward-euler";
  /// The 2-DOF PID's setpoint weights b (proportional), c (derivative), each
  /// in [0, 1] (docs/two_dof.md); 1, 1 = the 1-DOF PID.
  std::pair<double, double> setpoint_weights{1.0, 1.0};
  /// The first-order setpoint filter r / (Tr s + 1) before all three terms,
  /// Tr in s (docs/two_dof.md); 0 = none.
  double setpoint_filter_s = 0.0;

  /// The loop a tuning starts from: stability margin 0.01, because with a
  /// margin near zero the search parks poles a hair left of the imaginary
  /// axis, where the sampled objective cannot see them (docs/tuning.md).
  static LoopSpec ForTuning() {
    LoopSpec s;
    s.stability_margin = 0.01;
    return s;
  }

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit({"loop", "continuous (exact, ideal PID) or sampled (discrete PID at --dt, ZOH plant)", "", kNone,
              R"("sampled")"},
             &loop);
    a->Visit({"dt", "sampled-loop period; --sample-time must be a multiple", "s", kEpisode, "0.0005"}, &dt_s);
    a->Visit({"sample_time", "ts of eq. (4): spacing of the error samples", "s", kEpisode, "0.1"},
             &sample_time_s);
    a->Visit({"horizon", "n of eq. (4): last sample time", "s", kEpisode, "10"}, &horizon_s);
    a->Visit(
        {"reference",
         "size A of the reference step r(t) = A (1 = the paper's unit step); e = A - y in every objective, "
         "step metrics relative to the final value",
         "", kEpisode, "2"},
        &reference);
    a->Visit({"stability_margin",
              "strict stability: Re p < -margin*max(1,|p|), p = s-plane pole (sampled: p = log(z)/dt); "
              "with a dead time L, |p| counts up to pi/L",
              "", kNone, "0.001"},
             &stability_margin);
    a->Visit({"disturbance",
              "none|square|step|sine|noise|prbs|chirp at the plant input (default: square if an amplitude is "
              "given)",
              "", kEpisode, R"("sine")"},
             &disturbance);
    a->Visit({"disturbance_amplitude",
              "square and prbs +/-A, step height, sine and chirp peak or noise std deviation", "", kEpisode,
              "0.5"},
             &disturbance_amplitude);
    a->Visit({"disturbance_period", "square/sine period", "s", kEpisode, "3"}, &disturbance_period_s);
    a->Visit({"disturbance_phase", "time shift of the disturbance", "s", kEpisode, "0.25"},
             &disturbance_phase_s);
    a->Visit({"disturbance_step_time", "step disturbance time", "s", kEpisode, "1.5"},
             &disturbance_step_time_s);
    a->Visit({"noise_hold", "noise is held constant over this interval; the prbs's clock period", "s",
              kEpisode, "0.05"},
             &noise_hold_s);
    a->Visit({"seed",
              "seed of the noise and prbs disturbances and of the measurement noise (another stream), and of "
              "the search, for tune",
              "", kEpisode, "7"},
             &seed);
    a->Visit(
        {"chirp_band",
         "chirp: the linear sweep's start and end frequencies F0,F1, 0 <= F0 < F1 < 1/(2 dt) (sampled loop "
         "only)",
         "Hz", kEpisode, "[0.5, 4]"},
        &chirp_band);
    a->Visit({"chirp_duration", "chirp: sweep duration T (default 0: the horizon); n = 0 after T", "s",
              kEpisode, "4"},
             &chirp_duration_s);
    a->Visit(
        {"measurement_noise",
         "std deviation of seeded Gaussian noise on the measured y (from --seed, sampled loop only): the "
         "PID, the trajectory and IAE etc. see y + noise",
         "", kEpisode, "0.01"},
        &measurement_noise);
    a->Visit({"measurement_resolution",
              "resolution q of the measured y, a sensor's or an ADC's step (sampled loop only): the PID, the "
              "trajectory and IAE etc. see q round((y + noise) / q); 0 = exact",
              "", kEpisode, "0.01"},
             &measurement_resolution);
    a->Visit({"derivative_filter",
              "derivative filter time constant Tf, both loops: C(s) = kp + ki/s + kd s/(Tf s + 1); 0 = the "
              "paper's ideal PID",
              "s", kEpisode, "0.01"},
             &derivative_filter_s);
    a->Visit({"derivative_filter_ratio",
              "derivative filter by a ratio N: Tf = kd / (N kp) (Td / N), both loops, on the sampled loop at "
              "least dt; 0 = not used; excludes --derivative-filter",
              "", kEpisode, "10"},
             &derivative_filter_ratio);
    a->Visit({"output_limits", "sampled PID: output limits LO,HI", "", kEpisode | kInfinite, "[-5, 5]"},
             &output_limits);
    a->Visit({"anti_windup", "sampled PID: none|clamping|back-calculation", "", kEpisode, R"("none")"},
             &anti_windup);
    a->Visit({"derivative_on",
              "error|measurement, both loops: measurement is the setpoint weight c = 0 (--setpoint-weights)",
              "", kEpisode, R"("measurement")"},
             &derivative_on);
    a->Visit({"setpoint_weights",
              "2-DOF PID, both loops: setpoint weights B,C in [0, 1], u = kp (b r - y) + ki/s (r - y) + kd "
              "s/(tf s + 1) (c r - y) (docs/two_dof.md); 1,1 = the 1-DOF PID",
              "", kEpisode, "[0.6, 0]"},
             &setpoint_weights);
    a->Visit(
        {"setpoint_filter",
         "2-DOF PID, both loops: first-order setpoint filter time constant Tr, r_f = r/(Tr s + 1) in r's "
         "place in all three terms (docs/two_dof.md); 0 = none",
         "s", kEpisode, "2"},
        &setpoint_filter_s);
    a->Visit({"integral", "sampled PID: backward-euler|forward-euler|trapezoidal", "", kEpisode,
              R"("trapezoidal")"},
             &integral);
  }
};

/// Robustness bounds (docs/robustness.md): tune rejects a candidate that
/// breaks one; evaluate reports it in robustness.violations. +inf / 0: none.
struct BoundsSpec {
  double max_ms = kInf, max_mt = kInf, max_noise_gain = kInf;
  double min_phase_margin_deg = 0.0, min_gain_margin = 0.0, max_time_constant_s = kInf;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit({"max_ms", "bound on Ms = ||S||inf (e.g. 1.6)", "", kInfinite | kSearch, "1.6"}, &max_ms);
    a->Visit({"max_mt", "bound on Mt = ||T||inf (e.g. 1.3)", "", kInfinite | kSearch, "1.3"}, &max_mt);
    a->Visit({"max_noise_gain", "bound on the noise gain ||C S||inf (the ideal derivative's is unbounded)",
              "", kInfinite | kSearch, "500"},
             &max_noise_gain);
    a->Visit({"min_phase_margin", "least phase margin", "deg", kSearch, "30"}, &min_phase_margin_deg);
    a->Visit(
        {"min_gain_margin", "least gain margin, a factor > 1 (e.g. 2 = 6 dB; 0 = none)", "", kSearch, "2"},
        &min_gain_margin);
    a->Visit({"max_time_constant", "bound on the slowest closed-loop time constant 1/min|Re p|", "s",
              kInfinite | kSearch, "2.5"},
             &max_time_constant_s);
  }
};

/// How to search: method, objective, box, budgets, constraints, the robust
/// preset and the robust set.
struct TuneSpec {
  std::string method = "multi-start", objective = "iae";
  double load_weight = 1.0;
  std::pair<double, double> bounds{0.0, 30.0};
  int max_iter = 0, max_evals = 0, starts = 0, design_points = kDefaultDesignPoints, refine_starts = 2;
  bool adaptive = false;
  std::string refine = "ceres";
  double agree_tolerance = 1e-3;
  double max_overshoot_pct = kInf, max_settling_s = kInf;
  std::string zn_rule = "classic";
  std::string rule = "pid";
  bool robust = false;
  int robust_samples = 0;
  double robust_quantile = 1.0, robust_spread = 0.1;
  bool two_dof = false;
  double robustness = 1.4, response_time_s = 0.0, crossover_rad_s = 0.0, tau_c_s = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(
        {"method",
         "multi-start (Sobol' design + Nelder-Mead polish) | nelder-mead | paper-nm | ziegler-nichols | ga | "
         "pso-gsa | simc | amigo (tuning rules on a reduced model) | migo (the largest ki under an Ms "
         "bound) | optimal (the design engine: the least load integral |e| dt under Ms, Mt and noise-gain "
         "bounds, docs/tuning.md). Not given: optimal, on the continuous loop and on --loop sampled, unless "
         "a "
         "flag asks for a search (an objective, a box, a budget, a margin, a settling or time-constant "
         "bound, "
         "robust, --backend lcm) or the plant is the nonlinear stepper: then multi-start, and the line "
         "'method chosen' names the flag (docs/tuning.md, \"Any plant\")",
         "", kNone, R"("nelder-mead")"},
        &method);
    a->Visit({"objective",
              "iae | ise | itae | iae-continuous | load-iae (IAE of a unit step at the plant input, r = 0) | "
              "setpoint-load (iae + W load-iae)",
              "", kSearch, R"("ise")"},
             &objective);
    a->Visit({"load_weight", "W of --objective setpoint-load (>= 0)", "", kSearch, "2"}, &load_weight);
    a->Visit({"bounds",
              "gain box LO,HI for each of kp, ki, kd (not given: 0 to 10 x the largest AMIGO PID gain on the "
              "plant's half-rule model, or 0,30 where the rule does not apply; docs/tuning.md)",
              "", kSearch, "[0, 20]"},
             &bounds);
    a->Visit({"max_iter", "iteration budget (0 = method default; paper-nm: 100)", "", kSearch, "50"},
             &max_iter);
    a->Visit({"max_evals", "evaluation budget over all starts (0 = method default)", "", kSearch, "300"},
             &max_evals);
    a->Visit(
        {"starts", "seeded starts (nelder-mead, paper-nm; 0 = 4) or polished starts (multi-start; 0 = 16)",
         "", kSearch, "3"},
        &starts);
    a->Visit(
        {"design_points", "multi-start: Sobol' points of the design (at most half of --max-evals when given)",
         "", kSearch, "64"},
        &design_points);
    a->Visit({"refine_starts", "multi-start: Ceres from this many distinct polished minima, best first", "",
              kSearch, "1"},
             &refine_starts);
    a->Visit({"adaptive", "nelder-mead, multi-start: Gao & Han's adaptive coefficients", "", kSearch, "true"},
             &adaptive);
    a->Visit({"refine", "ceres | none: the least-squares cross-check", "", kSearch, R"("none")"}, &refine);
    a->Visit({"agree_tolerance", "relative objective difference for the 'agree' verdict", "", kNone, "0.01"},
             &agree_tolerance);
    a->Visit({"max_overshoot", "reject candidates overshooting more", "%", kInfinite | kSearch, "20"},
             &max_overshoot_pct);
    a->Visit({"max_settling", "reject candidates settling later", "s", kInfinite | kSearch, "10"},
             &max_settling_s);
    a->Visit({"zn_rule", "classic | pessen | some-overshoot | no-overshoot", "", kNone, R"("pessen")"},
             &zn_rule);
    a->Visit({"rule", "simc, amigo: pi | pid, the controller the rule gives", "", kNone, R"("pi")"}, &rule);
    a->Visit({"robust",
              "the robust preset (docs/robustness.md): --objective setpoint-load --load-weight 1 "
              "--derivative-filter-ratio 10 --max-ms 1.6 --max-time-constant <horizon/10>; a field given "
              "explicitly overrides its part",
              "", kSearch, "true"},
             &robust);
    a->Visit(
        {"robust_samples",
         "optimise over the nominal plant and N plants drawn as evaluate --monte-carlo draws them (seeded by "
         "--seed): the --robust-quantile of the objective over the set",
         "", kSearch, "5"},
        &robust_samples);
    a->Visit(
        {"robust_quantile", "quantile of the robust set's objective to minimise, (0, 1]; 1 = the worst case",
         "", kNone, "0.9"},
        &robust_quantile);
    a->Visit({"robust_spread", "relative spread of the robust set's draws, 10% or 0.1, in [0, 1)", "",
              kPercent, "0.2"},
             &robust_spread);
    a->Visit({"two_dof",
              "2-DOF PID (docs/two_dof.md): after the feedback gains, the setpoint weights b, c in [0, 1] "
              "minimising the setpoint step's IAE with the gains fixed; the result reports both responses",
              "", kSearch, "true"},
             &two_dof);
    a->Visit(
        {"robustness",
         "optimal and migo: the bound on Ms and Mt, in (1, 4]: lower is more robust and slower (not given: "
         "SIMC's Ms "
         "on the plant, within [1.4, 1.6]; 1.4 is a gain margin >= 3.5 and a phase margin >= 41 deg); or "
         "a phase margin in [20, 80] deg, e.g. 60 as MATLAB's pidtune: the largest Ms bound whose design "
         "keeps it",
         "", kNone, "1.6"},
        &robustness);
    a->Visit({"response_time",
              "optimal and migo: a slower design than --robustness allows, the loop's gain crossover at most "
              "2/T (0 = as "
              "fast as the bound allows)",
              "s", kNone, "5"},
             &response_time_s);
    a->Visit({"crossover",
              "optimal and migo: the response time as a gain crossover W, the same as --response-time 2/W (0 "
              "= as fast as "
              "the bound allows; not with --response-time)",
              "rad/s", kNone, "0.1"},
             &crossover_rad_s);
    a->Visit({"tau_c",
              "simc: the closed-loop time constant tau_c (0 = theta, the tight tuning; larger is slower and "
              "more robust; given, a plant without dead time is tuned too)",
              "s", kNone, "4"},
             &tau_c_s);
  }
};

/// `pidlab evaluate` / pidlab.evaluate: a plant, gains, a loop, bounds to
/// report, and an optional Monte Carlo over plants around this one.
struct EvaluateSpec {
  PlantSpec plant;
  std::vector<double> gains;  // kp, ki, kd
  LoopSpec loop;
  BoundsSpec bounds;
  int monte_carlo = 0;
  double spread = 0.1;

  template <typename Archive>
  void Serialize(Archive* a) {
    plant.Serialize(a);
    a->Visit({"gains", "KP,KI,KD (finite; all >= 0, or all <= 0 for a reverse-acting plant)", "", kEpisode, "[2, 1, 1.5]"}, &gains);
    loop.Serialize(a);
    bounds.Serialize(a);
    a->Visit(
        {"monte_carlo",
         "also evaluate the gains on N plants drawn around this one (seeded by --seed; stepper: each Table I "
         "parameter, other plants: each coefficient, uniformly within --spread)",
         "", kNone, "5"},
        &monte_carlo);
    a->Visit({"spread", "--monte-carlo: relative spread, as 10% or 0.1, in [0, 1)", "", kPercent, "0.2"},
             &spread);
  }
};

/// `pidlab tune` / pidlab.tune: a plant, a loop (stability margin 0.01),
/// bounds that reject candidates, and how to search.
struct TuningSpec {
  PlantSpec plant;
  LoopSpec loop = LoopSpec::ForTuning();
  BoundsSpec bounds;
  TuneSpec tune;

  template <typename Archive>
  void Serialize(Archive* a) {
    plant.Serialize(a);
    loop.Serialize(a);
    bounds.Serialize(a);
    tune.Serialize(a);
  }
};

}  // namespace pidlab::spec
