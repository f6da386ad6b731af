// pidlab identify: a process model (P1D, P2D, P2DU, P1DI, P2DZ, as MATLAB's idproc
// names them, or a general transfer function TF of --poles and --zeros) fitted to the t, u, y columns of a
// CSV (docs/identify.md, "Identifying a model from a CSV").

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "commands.h"
#include "identify_record.h"
#include "pidlab/figures/figures.h"
#include "pidlab/identify/csv_data.h"
#include "pidlab/identify/identify.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/results/identify_json.h"
#include "pidlab/spec/field.h"

namespace pidlab::cli {
namespace {

using identify::IdentifyResult;

std::string Num(double v, int precision = 8) {
  if (!std::isfinite(v)) return std::isnan(v) ? "-" : (v > 0 ? "inf" : "-inf");
  std::ostringstream os;
  os << std::setprecision(precision) << v;
  return os.str();
}

std::string Polynomial(const std::vector<double>& p) {
  std::string s = "[";
  for (std::size_t i = 0; i < p.size(); ++i) s += (i ? " " : "") + Num(p[i], 10);
  return s + "]";
}

// "b1 s + b0" or "s^3 + a2 s^2 + a1 s + a0": the tf's polynomials by name.
std::string TfPolynomial(char letter, int degree, bool monic) {
  std::string s;
  const auto power = [](int k) { return k == 0 ? std::string() : k == 1 ? " s" : " s^" + std::to_string(k); };
  if (monic) s = power(degree).substr(1);
  for (int k = monic ? degree - 1 : degree; k >= 0; --k)
    s += (s.empty() ? "" : " + ") + std::string(1, letter) + std::to_string(k) + power(k);
  return s;
}

std::string Formula(const identify::ProcessModel& model) {
  switch (model.kind) {
    case identify::ProcessModelKind::kTf:
      return "(" + TfPolynomial('b', model.zeros, false) + ") e^(-Td s) / (" +
             TfPolynomial('a', model.poles, true) + ")";
    case identify::ProcessModelKind::kP1D:
      return "Kp e^(-Td s) / (1 + Tp1 s)";
    case identify::ProcessModelKind::kP2D:
      return "Kp e^(-Td s) / ((1 + Tp1 s)(1 + Tp2 s))";
    case identify::ProcessModelKind::kP2DU:
      return "Kp e^(-Td s) / (1 + 2 Zeta Tw s + (Tw s)^2)";
    case identify::ProcessModelKind::kP1DI:
      return "Kp e^(-Td s) / (s (1 + Tp1 s))";
    case identify::ProcessModelKind::kP2DZ:
      return "Kp (1 + Tz s) e^(-Td s) / ((1 + Tp1 s)(1 + Tp2 s))";
  }
  return "";
}

std::string Table(const IdentifyResult& r) {
  std::ostringstream os;
  os << "model " << identify::ToString(r.model.kind) << ": " << Formula(r.model) << "\n"
     << std::left << std::setw(10) << "parameter" << std::setw(18) << "value"
     << "standard error\n";
  for (std::size_t i = 0; i < r.names.size(); ++i)
    os << std::setw(10) << r.names[i] << std::setw(18) << Num(r.values[i], 10)
       << (i < r.at_bound.size() && !r.at_bound[i].empty() ? "at its " + r.at_bound[i] + " bound (one-sided)"
                                                           : Num(r.standard_errors[i], 3))
       << "\n";
  if (!r.covariance_ok) os << "(no standard errors: " << r.covariance_message << ")\n";
  const TransferFunction tf = r.model.ToTransferFunction();
  os << "fit " << Num(r.fit_percent, 6) << " %, AIC " << Num(r.aic, 6) << " (N log(2 cost / N) + 2 p), cost "
     << Num(r.cost, 4) << "\n"
     << r.samples << " samples at dt " << Num(r.dt_s) << " s, offsets u0 " << Num(r.u0) << ", y0 "
     << Num(r.y0)
     << (r.y0_estimated ? " (estimated, standard error " + Num(r.y0_standard_error, 3) + ")" : "")
     << (r.u0_estimated ? ", u0 estimated (standard error " + Num(r.u0_standard_error, 3) + ")" : "") << "\n"
     << (r.sampling.uniform
             ? ""
             : "sampling is non-uniform (intervals " + Num(r.sampling.min_interval_s) + " to " +
                   Num(r.sampling.max_interval_s) +
                   " s, dt above is the mean): the exact response interval by interval is used\n")
     << (r.intersample == identify::Intersample::kZoh &&
                 r.initial_condition == identify::InitialCondition::kZero
             ? ""
             : "input " + identify::ToString(r.intersample) + " between samples, initial condition " +
                   identify::ToString(r.initial_condition) + "\n")
     << r.starts_at_best << " of " << r.starts << " starts reached the best cost (within 1e-8 relative)"
     << (r.nested_starts > 0
             ? "; " + std::to_string(r.nested_starts) + " of them from the contained model's fit" +
                   (r.loss == identify::Loss::kL2 ? "" : " or the l2 fit")
             : "")
     << (r.delay_profile_improved ? "; the delay's profile lowered it" : "")
     << (r.bounds_refit_improved ? "; refitting with the parameters at a bound held there lowered it" : "")
     << "\n"
     << "num " << Polynomial(tf.num) << " den " << Polynomial(tf.den) << " delay "
     << Num(r.model.delay_s(), 10) << " s\n";
  os << "poles (+- 1.96 standard errors):";
  for (const identify::PoleEstimate& p : identify::PoleEstimates(r)) {
    os << " " << Num(p.re, 7) << " (+-" << Num(1.96 * p.re_se, 2) << ")";
    if (p.im != 0.0)
      os << (p.im > 0 ? " + " : " - ") << Num(std::abs(p.im), 7) << "j (+-" << Num(1.96 * p.im_se, 2) << ")";
    os << ";";
  }
  os << "\n";
  return os.str();
}

// The rest chosen by AIC when u0 was not given, and a robust loss with the
// samples it down-weighted (the first 20 listed; all in the JSON).
std::string RestAndLossLines(const IdentifyResult& r) {
  std::ostringstream os;
  if (!r.rest_hypotheses.empty()) os << "u0 " << Num(r.u0) << ": " << r.u0_source << "\n";
  if (r.loss == identify::Loss::kL2) return os.str();
  os << "loss " << identify::ToString(r.loss) << ", scale " << Num(r.loss_scale, 6) << " ("
     << r.loss_scale_source << "); " << r.downweighted.size() << " samples down-weighted (weight < "
     << Num(identify::kDownweightedBelow) << ")";
  for (std::size_t i = 0; i < r.downweighted.size() && i < 20; ++i)
    os << (i ? ", " : ": ") << r.downweighted[i];
  os << (r.downweighted.size() > 20 ? ", ..." : "") << "\n";
  return os.str();
}

// "record decimated by 20 ...": one line when the record was longer than
// --max-samples, else nothing.
std::string DecimationLine(const identify::Decimation& d) {
  if (d.factor == 1) return "";
  return "record decimated by " + std::to_string(d.factor) + ": " + std::to_string(d.samples_read) +
         " samples to " + std::to_string(d.samples) + " (--max-samples " + std::to_string(d.max_samples) +
         "), u and y averaged over each interval; the starts on " + std::to_string(d.start_samples) +
         " samples, the best refitted on the " + std::to_string(d.samples) + "\n";
}

std::string WhitenessLine(const identify::Whiteness& w) {
  std::ostringstream os;
  os << "residuals: Ljung-Box Q " << Num(w.ljung_box_q, 5) << " over " << w.lags
     << " lags, p = " << Num(w.p_value, 3) << (w.white ? " (white at 5 %)" : " (NOT white at 5 %)") << "; "
     << w.outside_band << " of " << w.lags << " autocorrelations outside +-" << Num(w.band, 3) << "\n";
  return os.str();
}

struct IdentifyCommand {
  std::string csv, log, model, out, plot_path;
  std::string intersample = "zoh", initial = "zero", u0_text, loss = "l2", loss_scale_text;
  CLI::Option* poles_option = nullptr;
  CLI::Option* zeros_option = nullptr;
  std::vector<long> episode;
  bool json = false, quiet = false;
  identify::IdentifyOptions options;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Fit a process model to a record: the columns t (s, uniform or not), u and y of a CSV with a header "
        "(any "
        "order, other columns ignored), or one episode of an LCM log of the trio (the plant's input u + n "
        "and "
        "the measured y of every step). By default the record starts at rest at u0 = u[0], or at u = 0 "
        "when that fits with a lower AIC (both are fitted), and y0 is "
        "estimated with the model. Ceres "
        "fits the exact ZOH response with a continuous delay from several starts; --model auto fits every "
        "process kind (not tf) and keeps the lowest AIC; --model tf --poles N --zeros M fits a general "
        "transfer function (docs/identify.md).");
    app->add_option("--csv", csv, "the CSV file with columns t, u, y");
    app->add_option("--log", log, "an LCM log of the trio ('pidlab launch --log')");
    app->add_option("--episode", episode, "with --log: the episode id (needed when the log holds several)")
        ->expected(1);
    app->add_option("--model", model, "the model: " + identify::ProcessModelKindNames() + "|auto")
        ->required();
    poles_option = app->add_option("--poles", options.poles,
                                   "with --model tf: the number of poles n, 1.." +
                                       std::to_string(plant_sim::kMaxTfPoles) + " (required)");
    zeros_option = app->add_option("--zeros", options.zeros,
                                   "with --model tf: the number of zeros m, 0..n-1 (default 0)");
    app->add_option("--starts", options.starts, "starting points of the multi-start fit")
        ->capture_default_str();
    app->add_option("--seed", options.seed,
                    "digital shift of the starts' Sobol' design (0: the unshifted sequence)")
        ->capture_default_str();
    app->add_option(
        "--u0", u0_text,
        "the input's operating point: a number, or 'estimate' (fitted with the model, from the "
        "default as its start); default: the input the record rested at, u[0] or 0, whichever fits "
        "with the lower AIC; a log's: 0. A record whose u is "
        "constant is a step from u0 and needs it (a heater switched on at the first sample: --u0 0)");
    app->add_option("--y0", options.y0,
                    "the output's operating point (default: estimated with the model; a log's: 0)");
    app->add_option("--intersample", intersample,
                    "the input between samples: zoh (held) or foh (linear from one sample to the next; a "
                    "CSV only: the trio's plant holds its input)")
        ->capture_default_str();
    app->add_option("--initial-condition", initial,
                    "the state at the first sample: zero (at rest at u0), steady-state (at rest with u[0] "
                    "applied) or estimate (fitted with the model, the input before the record at u[0])")
        ->capture_default_str();
    app->add_option("--loss", loss,
                    "the loss on each residual: l2 (least squares), huber or cauchy (Ceres's HuberLoss, "
                    "CauchyLoss: robust to outliers such as a sensor's dropouts; the samples they "
                    "down-weight are listed)")
        ->capture_default_str();
    app->add_option("--loss-scale", loss_scale_text,
                    "with --loss huber or cauchy: the scale a in units of y, > 0 (default: 1.345 or 2.385 "
                    "robust standard deviations, 1.4826 MAD, of the l2 fit's residuals)");
    app->add_option("--max-samples", options.max_samples,
                    "the most samples a fit takes, " + std::to_string(identify::kMinMaxSamples) + ".." +
                        std::to_string(identify::kMaxMaxSamples) +
                        ": a longer record is decimated by the least integer factor that fits, u and y "
                        "averaged over each interval, and its starts run on an eighth of the limit (a tf's "
                        "on a quarter), the best refitted on the decimated record (said on stderr and in "
                        "the output)")
        ->capture_default_str();
    app->add_flag("--json", json, "print one JSON object");
    app->add_flag("--quiet", quiet,
                  "no progress lines (on a terminal, a fit that runs beyond 3 s says on stderr, once a "
                  "second, the model, the starts done and the best cost so far; a record beyond "
                  "--max-samples says so, and its progress, wherever stderr goes)");
    app->add_option("--out", out,
                    "also write the JSON object to this file (a model file for --plant model:FILE)");
    app->add_option("--plot", plot_path,
                    "also draw a PNG: measured and simulated output, residuals and their autocorrelation");
    return [this] { return Run(); };
  }

  mutable long chosen_episode = 0;

  // After 3 s (from the first start when `at_once`: a long record), at most
  // once a second: "pidlab identify: p2d: 9 of 17 starts, best cost 12.5
  // (4 s)" on stderr.
  static std::function<void(identify::ProcessModelKind, int, int, double)> ProgressPrinter(bool at_once) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto last = std::make_shared<Clock::time_point>(start - std::chrono::seconds(at_once ? 1 : 0));
    const auto wait = std::chrono::seconds(at_once ? 0 : 3);
    return [start, last, wait](identify::ProcessModelKind kind, int done, int total, double best) {
      const auto now = Clock::now();
      if (now - start < wait || now - *last < std::chrono::seconds(1)) return;
      *last = now;
      std::cerr << "pidlab identify: " << identify::ToString(kind) << ": " << done << " of " << total
                << " starts, best cost " << Num(best, 6) << " ("
                << std::chrono::duration_cast<std::chrono::seconds>(now - start).count() << " s)\n";
    };
  }

  // Progress on a terminal, or for a record beyond --max-samples (its
  // decimation said at once); otherwise a log or a test's captured stderr
  // keeps its one line (README, "Exit status and limits").
  void ShowProgress(std::size_t samples) {
    const bool long_record = samples > options.max_samples;
    if (quiet) return;
    if (long_record)
      std::cerr << "pidlab identify: " << samples << " samples, more than --max-samples "
                << options.max_samples << ": decimated by "
                << identify::DecimationFactor(samples, options.max_samples)
                << " (an anti-alias average) before the fit, its starts on "
                << identify::StartSamples(options.max_samples, model == "tf") << " samples\n";
    if (long_record || ::isatty(STDERR_FILENO)) options.progress = ProgressPrinter(long_record);
  }

  identify::IdentifyData ReadData() const {
    identify::IdentifyData data;
    if (!csv.empty()) {
      Require(ReadCsvRecord(csv, Source(), &data));
      return data;
    }
    replay::LogContents contents;
    if (const Status st = replay::ReadLog(log, replay::ReadOptions{}, &contents); !st.ok())
      throw BadInput("--log " + Quote(log) + ": " + st.message());
    // Without --episode: the one episode whose plant input u + n varies (an
    // evaluate run logs its undisturbed twin too, whose input is constant).
    std::vector<const replay::Episode*> found;
    for (const replay::Episode& e : contents.episodes)
      if (episode.empty() ? e.has_config && e.Complete() && EpisodeInputVaries(e)
                          : e.episode_id == episode[0])
        found.push_back(&e);
    if (!episode.empty() && found.empty())
      throw BadInput("--episode " + std::to_string(episode[0]) + " is not in " + Quote(log));
    if (found.empty())
      throw BadInput("--log " + Quote(log) + " holds no complete episode whose input u + n varies");
    if (found.size() > 1) {
      std::string ids;
      for (const replay::Episode* e : found) ids += (ids.empty() ? "" : ", ") + std::to_string(e->episode_id);
      throw BadInput("--log " + Quote(log) + " holds " + std::to_string(found.size()) +
                     " episodes with a varying input (" + ids + "): choose one with --episode");
    }
    chosen_episode = found[0]->episode_id;
    const replay::Episode& e = *found[0];
    if (!e.Complete())
      throw BadInput("--log " + Quote(log) + ": episode " + std::to_string(e.episode_id) +
                     " is incomplete: " + Truncate(e.CompletenessNote(), 200));
    return EpisodeRecord(e);
  }

  // --poles and --zeros: given with tf only, within their ranges.
  void CheckTfShape(identify::ProcessModelKind kind, bool automatic) const {
    const bool tf = !automatic && kind == identify::ProcessModelKind::kTf;
    for (const CLI::Option* o : {poles_option, zeros_option})
      if (!tf && o->count() > 0)
        throw BadInput(o->get_name() + " " + o->as<std::string>() + " applies to --model tf only, not " +
                       Quote(model));
    if (!tf) return;
    if (poles_option->count() == 0)
      throw BadInput("--model tf needs --poles N (1.." + std::to_string(plant_sim::kMaxTfPoles) + ")");
    if (options.poles < 1 || options.poles > plant_sim::kMaxTfPoles)
      throw BadInput("--poles " + std::to_string(options.poles) + " must be in 1.." +
                     std::to_string(plant_sim::kMaxTfPoles));
    if (options.zeros < 0 || options.zeros >= options.poles)
      throw BadInput("--zeros " + std::to_string(options.zeros) + " must be in 0.." +
                     std::to_string(options.poles - 1) + " (fewer than --poles " +
                     std::to_string(options.poles) + ")");
  }

  // --u0: a finite number, or 'estimate'.
  void ParseU0() {
    if (u0_text.empty()) return;
    if (u0_text == "estimate") {
      options.estimate_u0 = true;
      return;
    }
    std::size_t used = 0;
    try {
      options.u0 = std::stod(u0_text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != u0_text.size() || !std::isfinite(options.u0))
      throw BadInput("--u0 " + Quote(u0_text) + " must be a finite number or 'estimate'");
  }

  // --loss, and --loss-scale as a number (IdentifyOptions::IsValid checks
  // its range and that the loss is robust).
  void ParseLoss() {
    if (!identify::ParseLoss(loss, &options.loss))
      throw BadInput("--loss " + Quote(loss) + " must be l2, huber or cauchy");
    if (loss_scale_text.empty()) return;
    std::size_t used = 0;
    try {
      options.loss_scale = std::stod(loss_scale_text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != loss_scale_text.size() || !(options.loss_scale > 0.0))
      throw BadInput("--loss-scale " + Quote(loss_scale_text) +
                     " must be a number in (0, 1e12] (units of y)");
  }

  // The library's limits (IdentifyOptions::IsValid: --starts, after --u0 and
  // --y0 are read), its "starts = 0 must be ..." as the flag's "--starts 0 must be ...".
  void CheckOptions() const {
    std::string why;
    if (options.IsValid(&why)) return;
    const std::size_t eq = why.find(" = ");
    if (eq != std::string::npos && why.find(' ') == eq)
      why = spec::FlagName(why.substr(0, eq)) + " " + why.substr(eq + 3);
    throw BadInput(why);
  }

  std::string Source() const { return !csv.empty() ? "--csv " + Quote(csv) : "--log " + Quote(log); }

  int Run() {
    if (csv.empty() == log.empty()) throw BadInput("give exactly one of --csv FILE and --log FILE");
    if (!episode.empty() && log.empty()) throw BadInput("--episode applies to --log only");
    identify::ProcessModelKind kind = identify::ProcessModelKind::kP1D;
    const bool automatic = model == "auto";
    if (!automatic && !identify::Parse(model, &kind))
      throw BadInput("--model " + Quote(model) + " must be one of " + identify::ProcessModelKindNames() +
                     "|auto");
    CheckTfShape(kind, automatic);
    ParseU0();
    if (!std::isnan(options.y0) && !std::isfinite(options.y0))
      throw BadInput("--y0 " + Num(options.y0) + " must be finite");
    ParseLoss();
    CheckOptions();
    if (!identify::ParseIntersample(intersample, &options.intersample))
      throw BadInput("--intersample " + Quote(intersample) + " must be zoh or foh");
    if (!identify::ParseInitialCondition(initial, &options.initial_condition))
      throw BadInput("--initial-condition " + Quote(initial) + " must be zero, steady-state or estimate");
    if (!log.empty() && options.intersample == identify::Intersample::kFoh)
      throw BadInput("--intersample foh: a log's input u + n is held over each step by the plant (zoh)");
    if (!out.empty()) CheckOutputFile(out, "--out");
    if (!plot_path.empty()) CheckOutputFile(plot_path, "--plot");
    const identify::IdentifyData data = ReadData();
    // A log of the trio starts from the plant's zero state: its operating point is 0, not the first sample.
    if (!log.empty()) {
      if (std::isnan(options.u0)) options.u0 = 0.0;
      if (std::isnan(options.y0)) options.y0 = 0.0;
    }
    ShowProgress(data.y.size());
    results::IdentifyRun run;
    const Status status = results::RunIdentify(data, automatic ? "auto" : model, options, &run);
    if (status.code() == StatusCode::kInvalidInput) throw BadInput(Source() + ": " + status.message());
    Require(Status(status.code(), Source() + ": " + status.message()));
    const IdentifyResult& result = run.result;
    nlohmann::json& j = run.json;
    std::string header;
    if (automatic) {
      const identify::AutoResult& a = run.automatic;
      std::ostringstream os;
      os << "auto: " << a.reason << "\n";
      for (const identify::AutoCandidate& c : a.candidates)
        os << "  " << std::left << std::setw(6) << identify::ToString(c.kind)
           << (c.status.ok() ? "AIC " + Num(c.result.aic, 8) + ", fit " + Num(c.result.fit_percent, 6) + " %"
                             : "failed: " + c.status.message())
           << (c.set_aside.empty() ? "" : "; set aside: " + c.set_aside) << "\n";
      header = os.str();
    }
    if (!log.empty()) {
      j["source"] = {{"log", log}, {"episode", chosen_episode}};
      header = "log " + log + ", episode " + std::to_string(chosen_episode) + " (input u + n, measured y)\n" +
               header;
    } else {
      j["source"] = {{"csv", csv}};
    }
    if (!out.empty()) {
      WriteOutputFile(out, j.dump(1) + "\n");
    }
    if (!plot_path.empty()) {
      plot::Figure figure;
      std::string error;
      if (const Status st = figures::IdentifyFigure(run.data, result, &figure); !st.ok())
        throw std::runtime_error(st.message());
      figure.output_path = plot_path;
      Require(plot::DrawPng(figure));
    }
    for (const std::string& w : result.warnings) std::cerr << "warning: " << w << "\n";
    std::cout << (json ? j.dump() + "\n"
                       : header + DecimationLine(run.decimation) + Table(result) + RestAndLossLines(result) +
                             WhitenessLine(result.whiteness));
    return 0;
  }
};

}  // namespace

std::function<int()> RegisterIdentify(CLI::App* app) { return RegisterCommand<IdentifyCommand>(app); }

}  // namespace pidlab::cli
