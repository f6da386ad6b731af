#include "pidlab/report/identify_section.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "format.h"
#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"
#include "pidlab/plot/fit_figure.h"

using pidlab::evaluation::LoopOptions;

namespace pidlab::report {
namespace {

Plant Motor() {
  Plant p;
  if (const Status st = MakeNonlinearStepperPlant(NonlinearStepperOptions{}, &p); !st.ok())
    throw std::runtime_error("stepper_nonlinear: " + st.message());
  return p;
}

Plant Eq3() {
  Plant p;
  if (const Status st = MakePlant("stepper_motor", StepperMotorParameters{}, &p); !st.ok())
    throw std::runtime_error("stepper_motor: " + st.message());
  return p;
}

// The identified model as a plant whose draws come from its covariance
// (what --plant model:FILE reads).
Plant ModelPlant(const identify::IdentifyResult& fit) {
  Plant p;
  p.name = "model";
  p.tf = fit.model.ToTransferFunction();
  p.delay_s = fit.model.delay_s();
  auto model = std::make_shared<plant_sim::ProcessModelUncertainty>();
  model->kind = fit.model.kind;
  model->values = fit.values;
  if (fit.covariance_ok) model->covariance = fit.covariance;
  model->covariance_message = fit.covariance_message;
  p.model = model;
  return p;
}

LoopOptions ExperimentLoop(const IdentifySection& s) {
  LoopOptions o;
  o.loop = evaluation::LoopKind::kSampled;
  o.dt_s = s.dt_s;
  o.horizon_s = s.horizon_s;
  o.disturbance.kind = DisturbanceKind::kPrbs;
  o.disturbance.amplitude = s.amplitude_rad;
  o.disturbance.noise_hold_s = s.clock_s;
  o.disturbance.seed = s.seed;
  o.measurement_noise.sigma = s.noise_rad;
  o.measurement_noise.seed = s.seed;
  return o;
}

LoopOptions TuneLoop(const IdentifySection& s) {
  LoopOptions o;
  o.loop = evaluation::LoopKind::kSampled;
  o.dt_s = s.tune_dt_s;
  o.horizon_s = s.tune_horizon_s;
  return o;
}

// The open-loop experiment: the record the plant saw (u + n, measured y).
bool RunExperiment(IdentifySection* s, std::string* error) {
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  what.record_trajectory = true;
  evaluation::Evaluation ev;
  if (const Status st = evaluation::Evaluate(Motor(), PidGains{}, ExperimentLoop(*s), what, &ev); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  s->data = identify::IdentifyData{};
  for (std::size_t k = 0; k < ev.trajectory.size(); ++k) {  // steps 0 .. total_steps - 1
    s->data.t.push_back(static_cast<double>(k) * s->dt_s);  // as identify --log reads a log
    s->data.u.push_back(ev.trajectory[k].u + ev.trajectory[k].n);
    s->data.y.push_back(ev.trajectory[k].y);
  }
  return true;
}

void CompareWithEq3(IdentifySection* s) {
  const TransferFunction tf = Eq3().tf;
  s->eq3_dc_gain = tf.num.back() / tf.den.back();
  // The cubic's roots: the pair and the fast real pole.
  Eigen::Matrix3d companion = Eigen::Matrix3d::Zero();
  for (int j = 0; j < 3; ++j) companion(0, j) = -tf.den[static_cast<std::size_t>(j + 1)] / tf.den[0];
  companion(1, 0) = companion(2, 1) = 1.0;
  const Eigen::Vector3cd roots = companion.eigenvalues();
  for (int i = 0; i < 3; ++i) {
    if (roots[i].imag() > 0) s->eq3_pair_re = roots[i].real(), s->eq3_pair_im = roots[i].imag();
    if (roots[i].imag() == 0.0) s->eq3_fast_pole = roots[i].real();
  }
  const double kp = s->fit.values.at(0), kp_se = s->fit.standard_errors.at(0);
  s->dc_within = std::abs(kp - s->eq3_dc_gain) <= 1.96 * kp_se;
  s->poles = identify::PoleEstimates(s->fit);
  for (const identify::PoleEstimate& p : s->poles)
    if (p.im > 0)
      s->pair_within = std::abs(p.re - s->eq3_pair_re) <= 1.96 * p.re_se &&
                       std::abs(p.im - s->eq3_pair_im) <= 1.96 * p.im_se;
}

// `pidlab tune --robust [--robust-samples N] --seed --loop sampled --dt --horizon` on `plant`,
// then its gains on eq. (3) and on the motor.
bool TuneAndRun(const IdentifySection& s, const Plant& plant, int robust_samples, bool quick,
                std::uint64_t seed, IdentifyGainSet* set, std::string* error) {
  tune::TuneOptions o;
  o.seed = seed;
  o.loop = TuneLoop(s);
  if (quick) o.starts = 1;
  tune::ApplyRobustPreset(&o);
  o.robust_samples = robust_samples;
  if (const Status st = tune::Tune(plant, o, &set->tune); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  set->tuned = set->tune.stable;
  if (!set->tuned) return true;
  LoopOptions run = o.loop;
  run.reference = s.move_rad;
  evaluation::EvaluateOptions what;
  what.compute_iae_continuous = false;
  for (const bool motor : {false, true}) {
    const Plant target = motor ? Motor() : Eq3();
    evaluation::Evaluation ev;
    if (const Status st = evaluation::Evaluate(target, set->tune.gains, run, what, &ev); !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    analysis::LoopAnalysis a;
    if (const Status st =
            analysis::AnalyzeLoop(target, set->tune.gains, run, analysis::LoopAnalysisOptions{}, &a);
        !st.ok()) {
      if (error) *error = st.message();
      return false;
    }
    (motor ? set->motor_iae_per_unit : set->eq3_iae_per_unit) = ev.iae_per_unit;
    (motor ? set->motor_stable : set->eq3_stable) = ev.stability.stable;
    (motor ? set->motor_ms : set->eq3_ms) = a.ms;
  }
  return true;
}

std::string Gains(const PidGains& g) {
  return "kp " + Num(g.kp, 6) + ", ki " + Num(g.ki, 6) + ", kd " + Num(g.kd, 6) + ", Tf " + Num(g.tf, 4) +
         " s";
}

std::string PlusMinus(double v, double se, int digits) { return Num(v, digits) + " ± " + Num(1.96 * se, 2); }

}  // namespace

namespace {

// ComputeIdentifySection() with the refusal's message in *error.
bool ComputeIdentifySectionOrExplain(bool quick, std::uint64_t seed, IdentifySection* section,
                                     std::string* error) {
  IdentifySection& s = *section;
  s = IdentifySection{};
  if (quick) s.horizon_s = 1.0, s.robust_samples = 4;
  try {
    if (!RunExperiment(&s, error)) return false;
    identify::IdentifyOptions options;
    options.u0 = 0.0, options.y0 = 0.0;  // the motor starts at rest at its holding point, as a log's
    // The whole record, as the report's figures were fitted (30 000 samples,
    // over the interactive limit that would decimate it).
    options.max_samples = std::max(options.max_samples, s.data.t.size());
    const Status status = identify::Identify(s.data, plant_sim::ProcessModelKind::kP2DU, options, &s.fit);
    if (!status.ok()) {
      *error = "identify: " + status.message();
      return false;
    }
    CompareWithEq3(&s);
    s.on_model.name = "tuned on the identified model";
    s.on_eq3.name = "tuned on eq. (3)";
    return TuneAndRun(s, ModelPlant(s.fit), s.robust_samples, quick, seed, &s.on_model, error) &&
           TuneAndRun(s, Eq3(), 0, quick, seed, &s.on_eq3, error);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

}  // namespace

Status ComputeIdentifySection(bool quick, std::uint64_t seed, IdentifySection* section) {
  std::string why;
  if (!ComputeIdentifySectionOrExplain(quick, seed, section, &why)) return Status::RunnerFailed(why);
  return Status::Ok();
}

void RenderIdentifySection(std::ostream& os, const IdentifySection& s) {
  const identify::IdentifyResult& f = s.fit;
  os << "## Identifying the motor\n\n"
     << "The nonlinear stepper (stepper_nonlinear) as a motor nobody wrote down (docs/identify.md, \"End to "
        "end\"): an open-loop PRBS experiment of ±"
     << Num(s.amplitude_rad * 1e3, 3) << " mrad (one bit per " << Num(s.clock_s * 1e3, 3)
     << " ms) on the sampled loop at dt " << Num(s.dt_s * 1e3, 3) << " ms for " << Num(s.horizon_s, 3)
     << " s, with seeded noise σ = " << Num(s.noise_rad * 1e6, 3)
     << " µrad on the measured angle, run in process (the trio gives the same bits: integration.trio.excite; "
        "integration.trio.identify_motor runs it over the trio); a P2DU with delay fitted to it by `pidlab "
        "identify`; and `pidlab tune --robust` on the identified model (its robust set "
     << s.robust_samples
     << " plants drawn from the fit's covariance) against the same tune on eq. (3), on the sampled loop at "
        "dt "
     << Num(s.tune_dt_s * 1e3, 3) << " ms over " << Num(s.tune_horizon_s, 3) << " s.\n\n"
     << "| parameter | identified (± 95 %) |\n|---|---|\n";
  for (std::size_t i = 0; i < f.names.size(); ++i)
    os << "| " << f.names[i] << " | " << PlusMinus(f.values[i], f.standard_errors[i], 7) << " |\n";
  os << "\nFit " << Num(f.fit_percent, 6) << " %, residuals " << (f.whiteness.white ? "white" : "NOT white")
     << " (Ljung–Box p = " << Num(f.whiteness.p_value, 3) << "), " << f.starts_at_best << " of " << f.starts
     << " starts reached the optimum" << (f.arx_start ? " (the ARX start among the starts)" : "") << ".\n\n"
     << "| against eq. (3) | identified (± 95 %) | eq. (3) | within |\n|---|---|---|---|\n"
     << "| DC gain | " << PlusMinus(f.values[0], f.standard_errors[0], 7) << " | " << Num(s.eq3_dc_gain, 7)
     << " | " << (s.dc_within ? "yes" : "NO") << " |\n";
  for (const identify::PoleEstimate& p : s.poles)
    if (p.im > 0)
      os << "| pole pair | " << PlusMinus(p.re, p.re_se, 7) << " ± (" << PlusMinus(p.im, p.im_se, 8)
         << ") j | " << Num(s.eq3_pair_re, 7) << " ± " << Num(s.eq3_pair_im, 8) << " j | "
         << (s.pair_within ? "yes" : "NO") << " |\n";
  os << "\nEq. (3)'s third pole, " << Num(s.eq3_fast_pole, 6) << " rad/s (a lag of "
     << Num(-1e3 / s.eq3_fast_pole, 3)
     << " ms), is what the model's delay Td = " << Num(f.model.td_s * 1e3, 4) << " ms stands for.\n\n"
     << "| gains | " << s.on_model.name << " | " << s.on_eq3.name << " |\n|---|---|---|\n";
  const auto row = [&](const char* what, auto get) {
    os << "| " << what << " | " << get(s.on_model) << " | " << get(s.on_eq3) << " |\n";
  };
  row("gains",
      [](const IdentifyGainSet& g) { return g.tuned ? Gains(g.tune.gains) : std::string("no stable loop"); });
  row("Ms on eq. (3)", [](const IdentifyGainSet& g) { return Num(g.eq3_ms, 5); });
  row("Ms on the motor (its linearisation)", [](const IdentifyGainSet& g) { return Num(g.motor_ms, 5); });
  row("IAE/A on eq. (3)", [&](const IdentifyGainSet& g) { return Num(g.eq3_iae_per_unit, 7); });
  row("IAE/A on the motor", [&](const IdentifyGainSet& g) { return Num(g.motor_iae_per_unit, 7); });
  os << "\nIAE/A of a " << Num(s.move_rad, 3)
     << " rad step (eq. 4, e = A − y). Both gain sets keep Ms ≤ 1.6 on eq. (3) and on the motor: "
     << ((s.on_model.eq3_ms <= 1.6 && s.on_model.motor_ms <= 1.6 && s.on_eq3.eq3_ms <= 1.6 &&
          s.on_eq3.motor_ms <= 1.6)
             ? "yes"
             : "NO")
     << ".\n\n";
}

namespace {

// DrawIdentifyFigure() with the refusal's message in *caption.
bool DrawIdentifyFigureOrExplain(const IdentifySection& s, const std::string& out_dir,
                                 const std::string& file, std::string* caption, std::string* error) {
  plot::Figure figure;
  figure.title = "The motor identified: a P2DU with delay fitted to an open-loop PRBS experiment";
  const plot::FitTrace trace{s.data.t,
                             s.data.y,
                             s.fit.simulated,
                             s.fit.residuals,
                             s.fit.whiteness.autocorrelation,
                             s.fit.whiteness.band};
  if (const Status st = plot::MakeFitFigure(trace, "angle [rad]", &figure); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  figure.output_path = (std::filesystem::path(out_dir) / file).string();
  if (const Status st = plot::DrawPng(figure); !st.ok()) {
    if (error) *error = st.message();
    return false;
  }
  *caption =
      "Identifying the motor: the measured angle of the open-loop PRBS experiment on the nonlinear stepper "
      "with "
      "the identified P2DU's, the residuals, and their autocorrelation with the 95 % band of white noise.";
  return true;
}

}  // namespace

Status DrawIdentifyFigure(const IdentifySection& s, const std::string& out_dir, const std::string& file,
                          std::string* caption) {
  std::string why;
  if (!DrawIdentifyFigureOrExplain(s, out_dir, file, caption, &why)) return Status::IoFailed(why);
  return Status::Ok();
}

}  // namespace pidlab::report
