// The report's section "The motor itself": see motor_section.h.

#include "pidlab/report/motor_section.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "format.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"
#include "pidlab/plot/plot.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopGains;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledStep;
using pidlab::tune::ApplyRobustPreset;
using pidlab::tune::Tune;
using pidlab::tune::TuneMethod;
using pidlab::tune::TuneOptions;
using pidlab::tune::TuneSummary;

namespace pidlab::report {
namespace {

// The figure's curves: the first kCurveS of each response, every step; the
// panel without a limit shows the first kFastWindowS (the transient of the
// paper's gains rises in 0.2 ms), the limited one all of kCurveS every ms.
constexpr double kCurveS = 0.5;
constexpr double kFastWindowS = 0.02;
constexpr double kSlowStepS = 1e-3;
// Eq. (3) "holds" on the motor where the IAE/A agree within this.
constexpr double kHolds = 0.01;

std::string Gains(const PidGains& g) {
  return Num(g.kp, 6) + ", " + Num(g.ki, 6) + ", " + Num(g.kd, 6) +
         (g.tf > 0.0 ? ", Tf " + Num(g.tf, 4) : "");
}

Plant Motor(bool limited, double limit_v) {
  NonlinearStepperOptions o;
  if (limited) o.voltage_limit_v = limit_v;
  Plant p;
  if (const Status st = MakeNonlinearStepperPlant(o, &p); !st.ok())
    throw std::runtime_error("stepper_nonlinear: " + st.message());
  return p;
}

LoopOptions SampledLoop(const MotorSection& s, double reference) {
  LoopOptions o;
  o.loop = LoopKind::kSampled;
  o.dt_s = s.dt_s;
  o.pid = PidOptionsAt(o.pid, s.dt_s);
  o.sample_time_s = s.sample_time_s;
  o.horizon_s = s.horizon_s;
  o.reference = reference;
  return o;
}

// y(t)/A on [0, kCurveS] every kCurveStepS from a recorded trajectory.
MotorCurve CurveOf(const std::string& name, bool limited, const std::vector<SampledStep>& steps, double dt,
                   double reference) {
  MotorCurve c;
  c.name = name;
  c.limited = limited;
  (void)dt;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (steps[i].t > kCurveS + 1e-12) break;
    c.t.push_back(steps[i].t);
    c.y_per_unit.push_back(steps[i].y / reference);
  }
  return c;
}

bool RunRow(const MotorSection& s, const MotorGainSet& set, double move, bool limited, MotorRow* row,
            std::vector<SampledStep>* trajectory, std::string* error) {
  EvaluateOptions what;
  what.compute_iae_continuous = false;
  what.record_trajectory = trajectory != nullptr;
  Evaluation ev;
  if (const Status st =
          Evaluate(Motor(limited, s.voltage_limit_v), set.gains, SampledLoop(s, move), what, &ev);
      !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  row->move_rad = move;
  row->limited = limited;
  row->stable = ev.stability.stable;
  row->iae = ev.iae;
  row->iae_per_unit = ev.iae_per_unit;
  row->step_valid = ev.step.valid;
  row->rise_time_s = ev.step.rise_time_s;
  row->overshoot_pct = ev.step.overshoot_pct;
  row->settling_time_s = ev.step.settling_time_s;
  row->peak_phase_voltage_v = ev.motor.phase_voltage_v;
  row->peak_phase_current_a = ev.motor.phase_current_a;
  row->lost_steps = ev.lost_steps;
  row->final_error_rad = ev.final_error;
  row->ratio = set.eq3_iae_per_unit > 0 ? ev.iae_per_unit / set.eq3_iae_per_unit : NAN;
  if (trajectory) *trajectory = std::move(ev.trajectory);
  return true;
}

// Eq. (3) on the same sampled loop (A = 1); its trajectory if asked.
bool RunEq3(const MotorSection& s, MotorGainSet* set, std::vector<SampledStep>* trajectory,
            std::string* error) {
  Plant eq3;
  if (const Status st = MakePlant("stepper_motor", StepperMotorParameters{}, &eq3); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  EvaluateOptions what;
  what.compute_iae_continuous = false;
  what.record_trajectory = trajectory != nullptr;
  Evaluation ev;
  if (const Status st = Evaluate(eq3, set->gains, SampledLoop(s, 1.0), what, &ev); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  set->eq3_stable = ev.stability.stable;
  set->eq3_iae_per_unit = ev.iae_per_unit;
  set->eq3_rise_time_s = ev.step.valid ? ev.step.rise_time_s : NAN;
  set->eq3_overshoot_pct = ev.step.valid ? ev.step.overshoot_pct : NAN;
  set->eq3_settling_time_s = ev.step.valid ? ev.step.settling_time_s : NAN;
  if (trajectory) *trajectory = std::move(ev.trajectory);
  return true;
}

bool Holds(const MotorRow& r) { return r.stable && !r.lost_steps && std::abs(r.ratio - 1.0) <= kHolds; }

std::string MoveName(const MotorSection& s, double move) {
  if (move == s.tooth_pitch_rad) return Num(move, 4) + " (one tooth pitch)";
  return Num(move, 4);
}

// What one gain set does with or without the limit, in one sentence.
std::string Verdict(const MotorSection& s, const MotorGainSet& set, bool limited) {
  std::vector<const MotorRow*> rows;
  for (const MotorRow& r : set.rows)
    if (r.limited == limited) rows.push_back(&r);
  std::ostringstream os;
  os << (limited ? "With the " + Num(s.voltage_limit_v, 3) + " V limit, " : "Without a limit, ");
  const MotorRow* last_hold = nullptr;
  const MotorRow* first_fail = nullptr;
  for (const MotorRow* r : rows) {
    if (Holds(*r) && !first_fail) last_hold = r;
    if (!Holds(*r) && !first_fail) first_fail = r;
  }
  if (last_hold) {
    os << "eq. (3) holds (IAE/A within " << Num(100 * kHolds, 2) << " %) up to "
       << Num(last_hold->move_rad, 4) << " rad, at a peak phase voltage of "
       << Num(last_hold->peak_phase_voltage_v, 4) << " V";
    if (!limited && last_hold->peak_phase_voltage_v > s.voltage_limit_v)
      os << " (" << Num(last_hold->peak_phase_voltage_v / s.voltage_limit_v, 3) << " times a "
         << Num(s.voltage_limit_v, 3) << " V driver's supply)";
  } else {
    os << "eq. (3) does not hold even for the smallest move";
  }
  if (first_fail) {
    os << "; at " << MoveName(s, first_fail->move_rad) << " rad ";
    if (!first_fail->stable)
      os << "the linearised loop is unstable";
    else if (first_fail->lost_steps)
      os << "the motor **loses steps** (it ends " << Num(first_fail->final_error_rad, 3)
         << " rad from the reference)";
    else
      os << "the IAE/A is " << Num(first_fail->ratio, 3) << " times eq. (3)'s";
  }
  std::vector<std::string> lost;
  for (const MotorRow* r : rows)
    if (r->lost_steps && r != first_fail) lost.push_back(Num(r->move_rad, 4));
  if (!lost.empty()) {
    os << "; steps are also lost at";
    for (std::size_t i = 0; i < lost.size(); ++i) os << (i ? ", " : " ") << lost[i];
    os << " rad";
  }
  os << ".";
  return os.str();
}

void RenderSet(std::ostream& os, const MotorSection& s, const MotorGainSet& set) {
  os << "### " << set.name << ": kp, ki, kd = " << Gains(set.gains) << "\n\n" << set.origin << "\n\n";
  os << "Eq. (3) on the same loop: ";
  if (set.eq3_stable)
    os << "IAE/A " << Num(set.eq3_iae_per_unit, 6) << ", rise " << Num(1e3 * set.eq3_rise_time_s, 4)
       << " ms, overshoot " << Num(set.eq3_overshoot_pct, 4) << " %, settling "
       << Num(set.eq3_settling_time_s, 4) << " s (the same for every A).\n\n";
  else
    os << "unstable.\n\n";
  os << "| move A [rad] | voltage limit | IAE/A motor | IAE/A eq. (3) | motor / eq. (3) | rise [ms] | "
        "overshoot [%] | settling [s] | peak phase voltage [V] | peak phase current [A] | steps "
        "|\n|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const MotorRow& r : set.rows) {
    os << "| " << MoveName(s, r.move_rad) << " | " << (r.limited ? Num(s.voltage_limit_v, 3) + " V" : "none")
       << " | ";
    if (!r.stable) {
      os << "unstable | | | | | | | | |\n";
      continue;
    }
    os << Num(r.iae_per_unit, 6) << " | " << Num(set.eq3_iae_per_unit, 6) << " | " << Num(r.ratio, 4)
       << " | ";
    if (r.step_valid)
      os << Num(1e3 * r.rise_time_s, 4) << " | " << Num(r.overshoot_pct, 4) << " | "
         << Num(r.settling_time_s, 4);
    else
      os << "- | - | -";
    os << " | " << Num(r.peak_phase_voltage_v, 4) << " | " << Num(r.peak_phase_current_a, 3) << " | "
       << (r.lost_steps ? "**LOST**" : "kept") << " |\n";
  }
  os << "\n";
}

// The section's constants from Table I (tooth pitch, holding voltage), its
// horizon and its moves.
void StartSection(bool quick, MotorSection* s) {
  const NonlinearStepperOptions table_one;
  s->tooth_pitch_rad = table_one.motor.tooth_pitch_rad;
  s->holding_voltage_v = table_one.motor.resistance_ohm * table_one.motor.stationary_current_a;
  s->horizon_s = quick ? 1.0 : 3.0;
  s->moves = {0.001, 0.01, s->tooth_pitch_rad, 1.0};
}

MotorGainSet PaperSet(const PidGains& paper_nm) {
  MotorGainSet paper;
  paper.name = "The paper's Nelder-Mead gains (Table IV)";
  paper.origin = "Tuned by the paper on eq. (3) (continuous loop, unit step).";
  paper.gains = paper_nm;
  return paper;
}

// `pidlab tune --plant stepper_motor --method multi-start --seed <seed>`'s
// options: the paper's objective and box, asked for explicitly (the default
// method on eq. (3) is the design engine, optimal, since issue 57).
TuneOptions Eq3TuneOptions(bool quick, std::uint64_t seed) {
  TuneOptions d;
  d.seed = seed;
  if (quick) d.starts = 1;
  return d;
}

// pidlab's multi-start on the paper's objective of eq. (3).
bool DefaultSet(const Plant& eq3, const TuneOptions& d, std::uint64_t seed, MotorGainSet* set,
                std::string* error) {
  set->name = "pidlab's multi-start (the paper's objective)";
  TuneSummary ds;
  if (const Status st = Tune(eq3, d, &ds); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  set->gains = ds.gains;
  set->origin = "`pidlab tune --plant stepper_motor --method multi-start --seed " + std::to_string(seed) +
                "` (" + ToString(d.method) +
                " on eq. (3), the paper's continuous loop and objective, asked for explicitly: the default "
                "method is the design engine, optimal; IAE " +
                Num(ds.objective, 6) + ").";
  return true;
}

// `pidlab tune --robust` on eq. (3): designed on the continuous loop like
// the two sets before it, run with its derivative filter (tf) on this
// section's sampled loop. Also sets the section's robust_available and
// robust_note.
bool RobustSet(const Plant& eq3, const TuneOptions& d, std::uint64_t seed, MotorSection* s, MotorGainSet* set,
               std::string* error) {
  TuneOptions r = d;
  ApplyRobustPreset(&r);
  TuneSummary rs;
  if (const Status st = Tune(eq3, r, &rs); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  set->name = "pidlab's robust preset";
  set->gains = LoopGains(rs.gains, r.loop);
  set->origin = "`pidlab tune --plant stepper_motor --seed " + std::to_string(seed) +
                " --robust` (setpoint-load objective, derivative filter Tf = kd/(10 kp), Ms <= 1.6, slowest "
                "time constant <= 2.5 s, on eq. (3) and the paper's continuous loop; objective " +
                Num(rs.objective, 6) + "); the discrete PID here filters its derivative with that Tf.";
  s->robust_available = rs.stable;
  s->robust_note =
      "`pidlab tune --robust` (the robust preset, docs/robustness.md) is the third gain set: it filters its "
      "derivative (Tf = kd/(10 kp)), so its first-sample kick is bounded, unlike the ideal derivative of the "
      "other sets designed on eq. (3).";
  return true;
}

// Gain set k over every move with and without the limit, next to eq. (3);
// the curves of the paper's gains (k = 0) and of the motor-tuned gains
// (k = 3) at the tuned move.
bool RunGainSet(std::size_t k, MotorSection* section, std::string* error) {
  MotorSection& s = *section;
  MotorGainSet& set = s.sets[k];
  std::vector<SampledStep> eq3_steps;
  if (!RunEq3(s, &set, k == 0 ? &eq3_steps : nullptr, error)) return false;
  if (k == 0) {
    s.curves.push_back(CurveOf("eq. (3), any A", false, eq3_steps, s.dt_s, 1.0));
    s.curves.push_back(CurveOf("eq. (3), any A", true, eq3_steps, s.dt_s, 1.0));
  }
  for (const bool limited : {false, true}) {
    for (const double move : s.moves) {
      MotorRow row;
      const bool paper_curve = k == 0;
      const bool tuned_curve = k == 3 && limited && move == s.tune_move_rad;
      std::vector<SampledStep> steps;
      if (!RunRow(s, set, move, limited, &row, paper_curve || tuned_curve ? &steps : nullptr, error))
        return false;
      if (paper_curve || tuned_curve) {
        std::string name = (paper_curve ? "paper's gains, A = " : "motor-tuned gains, A = ") + Num(move, 4);
        if (row.lost_steps) name += " (lost steps)";
        s.curves.push_back(CurveOf(name, limited, steps, s.dt_s, move));
      }
      set.rows.push_back(row);
    }
  }
  return true;
}

// The tune on the motor: one tooth pitch under the voltage limit, the
// objective sampled every 5 ms over the first 0.5 s. Sets the section's
// tune_* fields.
TuneOptions MotorTuneOptions(bool quick, std::uint64_t seed, MotorSection* s) {
  TuneOptions t;
  t.method = TuneMethod::kNelderMead;
  t.starts = 1;
  t.max_evaluations = quick ? 30 : 80;
  t.seed = seed;
  s->tune_move_rad = s->tooth_pitch_rad;
  s->tune_horizon_s = 0.5;
  s->tune_sample_time_s = 0.005;
  t.loop.loop = LoopKind::kSampled;
  t.loop.dt_s = s->dt_s;
  t.loop.pid = PidOptionsAt(t.loop.pid, s->dt_s);
  t.loop.sample_time_s = s->tune_sample_time_s;
  t.loop.horizon_s = s->tune_horizon_s;
  t.loop.reference = s->tune_move_rad;
  return t;
}

// The gain set of the tune on the motor (s.motor_tune, run with options t).
MotorGainSet OnMotorSet(const MotorSection& s, const TuneOptions& t, std::uint64_t seed) {
  MotorGainSet on_motor;
  on_motor.name = "Tuned on the motor itself";
  on_motor.gains = s.motor_tune.gains;
  std::ostringstream origin;
  origin << "`pidlab tune --plant stepper_nonlinear --voltage-limit " << Num(s.voltage_limit_v, 3)
         << " --loop sampled --dt " << Num(s.dt_s, 4) << " --reference " << Num(s.tune_move_rad, 17)
         << " --horizon " << Num(s.tune_horizon_s, 4) << " --sample-time " << Num(s.tune_sample_time_s, 4)
         << " --method nelder-mead --starts 1 --max-evals " << t.max_evaluations << " --seed " << seed
         << "`: the IAE of e = A - y for a tooth-pitch move through the limited drive ("
         << s.motor_tune.evaluations << " evaluations of the nonlinear motor, objective "
         << Num(s.motor_tune.objective, 6) << (s.motor_tune.stable ? "" : ", **no stable loop found**")
         << "; no Ceres refinement: it differentiates linear loops only).";
  on_motor.origin = origin.str();
  return on_motor;
}

// What the section covers: the motor, the drive, the loop, the moves, the
// voltage limit and what "steps lost" means.
void RenderIntroduction(std::ostream& os, const MotorSection& s) {
  os << "## The motor itself\n\n"
     << "Everything above judges gains on eq. (3), the small-signal linearisation of the stepper about its "
        "holding point. Here the same gains drive the nonlinear two-phase PM stepper (`--plant "
        "stepper_nonlinear`, Bodson et al. 1993 with Table I; docs/stepper.md derives it and shows that its "
        "linearisation is eq. (3)). u is the commanded rotor angle, turned into the two phase voltages by a "
        "voltage-mode drive (the microstep table linearised at the holding point). Loop: the sampled loop "
        "(discrete PID, dt = "
     << Num(s.dt_s, 4) << " s), IAE of eq. (4) with e = A - y sampled every " << Num(s.sample_time_s, 4)
     << " s over " << Num(s.horizon_s, 4)
     << " s, and the same loop on eq. (3) beside it (on a linear loop IAE/A does not depend on A). Moves: "
        "0.001 and 0.01 rad (small, where eq. (3) should hold), one tooth pitch lambda = "
     << Num(s.tooth_pitch_rad, 6) << " rad, and the paper's 1 rad step (almost four tooth pitches).\n\n"
     << "**Voltage limit: " << Num(s.voltage_limit_v, 3)
     << " V per phase.** Drivers for a motor of this size (0.15 A holding current, 33 ohm phases) run from "
        "12-24 V supplies; 24 V is the common upper value, and the holding point alone needs r I_o = "
     << Num(s.holding_voltage_v, 3)
     << " V, so 24 V leaves about five times that for moving. Without a limit the drive is ideal: it "
        "applies whatever voltage the PID asks for, which no real driver does. \"Steps lost\" means the "
        "rotor is half a tooth pitch or more from the reference somewhere in the last tenth of the horizon "
        "(it settled at another detent or never settled); such a run is marked, not scored as a good "
        "one.\n\n"
     << s.robust_note << "\n\n";
}

// "In short": the paper's gains, and the paper's 1 rad step for every set.
void RenderHeadline(std::ostream& os, const MotorSection& s) {
  const MotorGainSet& paper = s.sets.front();
  const MotorRow* hold = nullptr;
  const MotorRow* small_limited = nullptr;
  for (const MotorRow& r : paper.rows) {
    if (!r.limited && Holds(r)) hold = &r;
    if (r.limited && (!small_limited || r.move_rad < small_limited->move_rad)) small_limited = &r;
  }
  int lost_unit = 0, sets_unit = 0;
  for (const MotorGainSet& set : s.sets)
    for (const MotorRow& r : set.rows)
      if (r.limited && r.move_rad == 1.0) {
        ++sets_unit;
        lost_unit += r.lost_steps ? 1 : 0;
      }
  os << "**In short:** ";
  if (hold)
    os << "eq. (3) describes the motor under the paper's gains only for moves up to "
       << Num(hold->move_rad, 3) << " rad, and only through a drive that can apply "
       << Num(hold->peak_phase_voltage_v, 4) << " V. ";
  else
    os << "eq. (3) does not describe the motor under the paper's gains for any move here. ";
  if (small_limited)
    os << "Through a " << Num(s.voltage_limit_v, 3) << " V driver their IAE/A is "
       << Num(small_limited->ratio, 3) << " times what eq. (3) predicts already at "
       << Num(small_limited->move_rad, 3) << " rad. ";
  if (sets_unit > 0)
    os << "On the paper's 1 rad step (" << Num(1.0 / s.tooth_pitch_rad, 3) << " tooth pitches) "
       << (lost_unit == sets_unit
               ? std::string("every gain set here loses steps")
               : std::to_string(lost_unit) + " of " + std::to_string(sets_unit) + " gain sets lose steps")
       << " with the limited drive.";
  os << "\n\n";
}

// The paper's gains on the motor against eq. (3) without a limit, and why
// the drive's peak voltage grows with the move.
void RenderLinearisationNotes(std::ostream& os, const MotorSection& s) {
  const MotorGainSet& paper = s.sets.front();
  os << "The paper's gains, motor against eq. (3) without a limit:";
  for (const MotorRow& r : paper.rows) {
    if (r.limited) continue;
    os << " " << Num(r.move_rad, 4) << " rad: IAE/A " << Num(r.iae_per_unit, 6) << " vs "
       << Num(paper.eq3_iae_per_unit, 6) << " (" << Num(100 * (r.ratio - 1.0), 3) << " %"
       << (r.lost_steps ? ", steps lost" : "") << ");";
  }
  os << " a difference within 1 % means eq. (3) describes the motor for that move.\n\n";
  const MotorRow* small = nullptr;
  for (const MotorRow& r : paper.rows)
    if (!r.limited && (!small || r.move_rad < small->move_rad)) small = &r;
  if (small) {
    os << "Eq. (3) has no voltage limit and no notion of a tooth pitch: it scales every move linearly. On "
          "the motor the drive's peak voltage grows with the move: the unfiltered derivative of the "
          "discrete "
          "PID puts kd A / dt = "
       << Num(paper.gains.kd * small->move_rad / s.dt_s, 4)
       << " rad of commanded angle on the first sample of a " << Num(small->move_rad, 3)
       << " rad step, hence " << Num(small->peak_phase_voltage_v, 4) << " V there";
    if (small->peak_phase_voltage_v > s.voltage_limit_v)
      os << ", beyond a " << Num(s.voltage_limit_v, 3)
         << " V driver already for the smallest move: the limited rows are what a real motor with these "
            "gains "
            "does";
    os << ".\n\n";
  }
}

}  // namespace

namespace {

// ComputeMotorSection() with the refusal's message in *error.
bool ComputeMotorSectionOrExplain(const PidGains& paper_nm, bool quick, std::uint64_t seed,
                                  MotorSection* section, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  MotorSection& s = *section;
  s = MotorSection{};
  StartSection(quick, &s);

  // The gain sets: the paper's, pidlab's multi-start on eq. (3), its robust
  // preset, one tuned on the motor.
  s.sets.push_back(PaperSet(paper_nm));
  const TuneOptions d = Eq3TuneOptions(quick, seed);
  Plant eq3;
  if (const Status st = MakePlant("stepper_motor", StepperMotorParameters{}, &eq3); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  MotorGainSet pidlab_default;
  if (!DefaultSet(eq3, d, seed, &pidlab_default, error)) return false;
  s.sets.push_back(pidlab_default);
  MotorGainSet robust;
  if (!RobustSet(eq3, d, seed, &s, &robust, error)) return false;
  s.sets.push_back(robust);

  // The tune on the motor, on its own thread while the other three sets run.
  const TuneOptions t = MotorTuneOptions(quick, seed, &s);
  const Plant limited_motor = Motor(true, s.voltage_limit_v);
  auto tune = std::async(std::launch::async,
                         [&limited_motor, t, &s] { return Tune(limited_motor, t, &s.motor_tune).message(); });
  const bool others = RunGainSet(0, &s, error) && RunGainSet(1, &s, error) && RunGainSet(2, &s, error);
  const std::string tune_error = tune.get();
  if (!others) return false;
  if (!tune_error.empty()) {
    *error = "tune on the motor: " + tune_error;
    return false;
  }
  s.sets.push_back(OnMotorSet(s, t, seed));
  if (!RunGainSet(3, &s, error)) return false;
  s.compute_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace

Status ComputeMotorSection(const PidGains& paper_nm, bool quick, std::uint64_t seed, MotorSection* section) {
  std::string why;
  if (!ComputeMotorSectionOrExplain(paper_nm, quick, seed, section, &why)) return Status::RunnerFailed(why);
  return Status::Ok();
}

void RenderMotorSection(std::ostream& os, const MotorSection& s) {
  RenderIntroduction(os, s);
  for (const MotorGainSet& set : s.sets) RenderSet(os, s, set);
  os << "### Where the linear design fails\n\n";
  if (!s.sets.empty()) RenderHeadline(os, s);
  for (const MotorGainSet& set : s.sets)
    os << "* **" << set.name << "**: " << Verdict(s, set, false) << " " << Verdict(s, set, true) << "\n";
  os << "\n";
  if (!s.sets.empty()) RenderLinearisationNotes(os, s);
}

namespace {

// DrawMotorFigure() with the refusal's message in *caption.
bool DrawMotorFigureOrExplain(const MotorSection& s, const std::string& out_dir, const std::string& file,
                              std::string* caption, std::string* error) {
  plot::Figure fig;
  fig.title = "Nonlinear stepper against eq. (3): y(t)/A for the paper's Nelder-Mead gains";
  fig.output_path = (std::filesystem::path(out_dir) / file).string();
  static const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"};
  for (const bool limited : {false, true}) {
    plot::Panel& p = fig.panels.emplace_back();
    p.title = limited ? "drive limited to " + Num(s.voltage_limit_v, 3) + " V per phase, first " +
                            Num(1e3 * kCurveS, 3) + " ms"
                      : "no voltage limit, first " + Num(1e3 * kFastWindowS, 3) + " ms";
    p.x_label = "t [ms]";
    p.y_label = "y(t) / A";
    p.y_min = -0.5;
    p.y_max = 2.0;
    std::size_t color = 0;
    const double window = limited ? kCurveS : kFastWindowS;
    const auto every =
        limited ? static_cast<std::size_t>(std::max(1.0, std::round(kSlowStepS / s.dt_s))) : std::size_t{1};
    for (const MotorCurve& c : s.curves) {
      if (c.limited != limited || c.t.empty()) continue;
      std::vector<double> t_ms, y;
      for (std::size_t i = 0; i < c.t.size() && c.t[i] <= window + 1e-12; i += every) {
        t_ms.push_back(1e3 * c.t[i]);
        y.push_back(c.y_per_unit[i]);
      }
      const bool eq3 = c.name.rfind("eq. (3)", 0) == 0;
      p.series.push_back({c.name, t_ms, y, eq3 ? plot::Style::kDashed : plot::Style::kLines,
                          eq3 ? "black" : kPalette[color++ % (sizeof(kPalette) / sizeof(kPalette[0]))]});
    }
  }
  if (const Status st = plot::DrawPng(fig); !st.ok()) {
    *error = "figure " + fig.output_path + ": " + st.message();
    return false;
  }
  *caption =
      "The motor itself: y(t)/A of the nonlinear stepper for the paper's Nelder-Mead gains at each move "
      "against eq. (3)'s response (dashed, the same for every A): without a limit over the first " +
      Num(1e3 * kFastWindowS, 3) + " ms (every step), with the " + Num(s.voltage_limit_v, 3) +
      " V limit over the first " + Num(1e3 * kCurveS, 3) +
      " ms, where the gains tuned on the motor at one tooth pitch are shown too. The y axis is cut at -0.5 "
      "and 2.";
  return true;
}

}  // namespace

Status DrawMotorFigure(const MotorSection& s, const std::string& out_dir, const std::string& file,
                       std::string* caption) {
  std::string why;
  if (!DrawMotorFigureOrExplain(s, out_dir, file, caption, &why)) return Status::IoFailed(why);
  return Status::Ok();
}

}  // namespace pidlab::report
