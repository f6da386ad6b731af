#include "cli_common.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>

#include "pidlab/plant_sim/plants.h"
#include "pidlab/transport/wire.h"

using pidlab::analysis::AnalyzeLoop;
using pidlab::analysis::Cancellation;
using pidlab::analysis::LoopAnalysis;
using pidlab::analysis::LoopAnalysisOptions;
using pidlab::analysis::LoopBounds;
using pidlab::analysis::LoopBoundsViolations;
using pidlab::episode_client::EpisodeClient;
using pidlab::episode_client::EpisodeClientOptions;
using pidlab::episode_client::EpisodePool;
using pidlab::episode_client::SplitUrlList;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::kMaxLoopSteps;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;

namespace pidlab::cli {

// The CLI's limits agree with the wire format's (the libraries below cannot
// see each other's headers).
static_assert(kMaxTransferFunctionCoefficients == transport::kMaxPolynomialCoefficients,
              "plant_sim and transport disagree on the longest polynomial");
static_assert(kMaxLoopSteps == transport::kMaxEpisodeSteps,
              "the sampled loop and the trio disagree on the longest episode");
static_assert(kMaxGain == kMaxInputMagnitude && kMaxCoefficientMagnitude == kMaxInputMagnitude &&
                  kMaxDisturbanceMagnitude == kMaxInputMagnitude,
              "one magnitude limit for every number typed");

namespace {

// "" if `text` is a finite number within kMaxInputMagnitude, else why not.
std::string CheckNumberText(const std::string& text, bool allow_infinite) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (text.empty() || end == begin || *end != '\0' || std::isnan(v)) return Quote(text) + " is not a number";
  if (std::isinf(v) && allow_infinite && errno != ERANGE) return "";
  if (errno == ERANGE || !std::isfinite(v) || std::abs(v) > kMaxInputMagnitude) {
    std::ostringstream os;
    os << Quote(text) << " is out of range: numbers must be finite and at most " << kMaxInputMagnitude
       << " in magnitude";
    return os.str();
  }
  return "";
}

}  // namespace

// The validators have no description, so that --help is unchanged.
CLI::Validator FiniteNumber() {
  return CLI::Validator([](std::string& text) { return CheckNumberText(text, false); }, "", "finite number");
}

CLI::Validator NumberOrInfinity() {
  return CLI::Validator([](std::string& text) { return CheckNumberText(text, true); }, "", "number or inf");
}

CLI::Validator WholeNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const bool digits =
            !text.empty() && text.size() <= 20 && text.find_first_not_of("0123456789") == std::string::npos;
        errno = 0;
        if (digits) std::strtoull(text.c_str(), nullptr, 10);
        if (!digits || errno == ERANGE)
          return Quote(text) + " must be a whole number from 0 to 18446744073709551615";
        return "";
      },
      "", "whole number");
}

void CheckOutputFile(const std::string& path, const std::string& flag) {
  if (path.empty()) return;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw BadInput(flag + " " + Quote(path) + " is a folder, not a file");
  if (Status s = io::CheckWritableTarget(path); !s.ok()) throw BadInput(flag + " " + s.message());
  const bool existed = std::filesystem::exists(std::filesystem::symlink_status(path, ec));
  // O_NONBLOCK: a FIFO without a reader fails with ENXIO instead of blocking.
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_NONBLOCK | O_CLOEXEC, 0666);
  if (fd < 0) {
    if (errno == ENXIO) return;
    throw BadInput(flag + " " + Quote(path) + " cannot be written: " + std::strerror(errno));
  }
  ::close(fd);
  if (!existed) std::remove(path.c_str());
}

void PrepareOutputDir(const std::string& dir, const std::string& flag) {
  if (dir.empty()) throw BadInput(flag + " must name a folder");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw BadInput(flag + " " + Quote(dir) + " cannot be created: " + ec.message());
  if (!std::filesystem::is_directory(dir, ec)) throw BadInput(flag + " " + Quote(dir) + " is not a folder");
  std::string probe = (std::filesystem::path(dir) / ".pidlab-write-test-XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw BadInput(flag + " " + Quote(dir) + " cannot be written: " + std::strerror(errno));
  ::close(fd);
  std::remove(probe.c_str());
}

std::string FromEnv(const std::string& flag, const char* env, const char* fallback) {
  if (!flag.empty()) return flag;
  const char* v = std::getenv(env);
  return v && *v ? v : fallback;
}

namespace {

struct NoteBoard {
  std::mutex mutex;
  bool quiet = false, verbose = false;
  long rerun = 0, left_out = 0, other = 0;
};
NoteBoard& Board() {
  static NoteBoard board;
  return board;
}

std::string Count(long n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

void SetRunNoteMode(bool quiet, bool verbose) {
  std::lock_guard<std::mutex> lock(Board().mutex);
  Board().quiet = quiet;
  Board().verbose = verbose;
}

void AddRunNote(const std::string& note) {
  NoteBoard& b = Board();
  std::lock_guard<std::mutex> lock(b.mutex);
  if (note.find("runs on another trio") != std::string::npos)
    ++b.left_out;
  else if (note.find("failed") != std::string::npos)
    ++b.rerun;
  else
    ++b.other;
  if (b.verbose && !b.quiet) std::cerr << "pidlab: note: " << Truncate(note, 280) << "\n";
}

void FlushRunNotes() {
  NoteBoard& b = Board();
  std::lock_guard<std::mutex> lock(b.mutex);
  std::vector<std::string> parts;
  if (b.rerun) parts.push_back(Count(b.rerun, "episode run again", "episodes run again"));
  if (b.left_out) parts.push_back(Count(b.left_out, "trio left out", "trios left out"));
  if (b.other) parts.push_back(Count(b.other, "other note", "other notes"));
  if (!parts.empty() && !b.quiet && !b.verbose) {
    std::string line = "pidlab: note: ";
    for (std::size_t i = 0; i < parts.size(); ++i) line += (i ? ", " : "") + parts[i];
    std::cerr << line << " (-v shows each)\n";
  }
  b.rerun = b.left_out = b.other = 0;
}

void LcmFlags::Register(CLI::App* app) {
  app->add_flag("--quiet,-q", quiet, "--backend lcm: say nothing of episodes run again or trios left out");
  app->add_flag("--verbose,-v", verbose,
                "--backend lcm: say each episode run again and each trio left out as it happens (default: "
                "their count, once); evaluate: also the id of each episode it ran");
  app->add_option("--lcm-url", lcm_url,
                  "--backend lcm: LCM URL of the trio (default $PIDLAB_LCM_URL, else LCM's); tune: one or "
                  "several trios, comma-separated (default: every trio of 'pidlab launch --trios K', "
                  "$PIDLAB_LCM_URLS)");
  app->add_option("--channel-prefix", channel_prefix,
                  "--backend lcm: channel prefix of the trio (default $PIDLAB_CHANNEL_PREFIX, else PIDLAB_)");
  app->add_option("--episode-timeout", episode_timeout_s,
                  "--backend lcm: give up on an episode after this many s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option(
         "--silence-deadline", silence_deadline_s,
         "--backend lcm: an episode fails after this many s without progress, naming the silent process")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option(
         "--max-attempts", max_attempts,
         "--backend lcm: run a failed episode again (as a new episode) up to this many attempts in all")
      ->capture_default_str();
  app->add_option(
      "--auth-key", auth_key_file,
      "--backend lcm: authenticate every message with the key in this file (docs/security.md; default "
      "$PIDLAB_AUTH_KEY_FILE)");
}

std::unique_ptr<EpisodeClient> LcmFlags::MakeClient() const {
  auto client = std::make_unique<EpisodeClient>(ClientOptions(Url()));
  Require(client->status());  // LCM did not start: exit 1
  return client;
}

std::string LcmFlags::Url() const {
  const std::vector<std::string> urls =
      SplitUrlList(FromEnv(lcm_url, "PIDLAB_LCM_URL", transport::kDefaultLcmUrl));
  if (urls.empty()) throw BadInput("--lcm-url " + Quote(lcm_url) + " names no URL");
  return urls.front();
}

std::unique_ptr<EpisodePool> LcmFlags::MakePool() const {
  // --lcm-url (one URL or several), else every trio of `pidlab launch
  // --trios K` ($PIDLAB_LCM_URLS), else $PIDLAB_LCM_URL, else LCM's.
  std::string list = lcm_url;
  if (list.empty()) list = FromEnv("", "PIDLAB_LCM_URLS", "");
  if (list.empty()) list = FromEnv("", "PIDLAB_LCM_URL", transport::kDefaultLcmUrl);
  const std::vector<std::string> urls = SplitUrlList(list);
  if (urls.empty()) throw BadInput("--lcm-url " + Quote(lcm_url) + " names no URL");
  std::vector<EpisodeClientOptions> trios;
  for (const std::string& url : urls) trios.push_back(ClientOptions(url));
  auto pool = std::make_unique<EpisodePool>(trios);
  Require(pool->status());  // a trio's LCM did not start: exit 1
  return pool;
}

EpisodeClientOptions LcmFlags::ClientOptions(const std::string& url) const {
  EpisodeClientOptions co;
  co.lcm_url = url;
  co.transport.channel_prefix =
      FromEnv(channel_prefix, "PIDLAB_CHANNEL_PREFIX", transport::kDefaultChannelPrefix);
  co.episode_timeout_s = episode_timeout_s;
  co.recovery.silence_deadline_s = silence_deadline_s;
  co.max_attempts = max_attempts;
  if (quiet && verbose) throw BadInput("--quiet and --verbose exclude each other");
  SetRunNoteMode(quiet, verbose);
  co.on_note = [](const std::string& note) { AddRunNote(note); };
  std::string error;
  const std::string key_file = FromEnv(auth_key_file, transport::kAuthKeyFileEnv, "");
  if (!key_file.empty()) {
    transport::AuthKey key;
    if (const Status st = transport::LoadAuthKey(key_file, &key); !st.ok()) throw BadInput(st.message());
    co.transport.auth_key = key;
  }
  if (!co.IsValid(&error)) throw BadInput(error);
  return co;
}

double ParseDouble(const std::string& text, const std::string& what, bool allow_infinite) {
  const std::string why = CheckNumberText(text, allow_infinite);
  if (!why.empty()) throw BadInput(what + " " + why);
  return std::strtod(text.c_str(), nullptr);
}

std::vector<double> ParseList(const std::string& text, const std::string& what, bool allow_infinite) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(ParseDouble(item, what, allow_infinite));
  if (out.empty() || (!text.empty() && text.back() == ','))
    throw BadInput(what + " " + Quote(text) + " must be a comma-separated list of numbers");
  return out;
}

double ParseSpread(const std::string& text, const std::string& flag) {
  const bool percent = !text.empty() && text.back() == '%';
  const double v = ParseDouble(percent ? text.substr(0, text.size() - 1) : text, flag);
  const double spread = percent ? v / 100.0 : v;
  if (!(spread >= 0.0) || !(spread < 1.0)) throw BadInput(flag + " " + Quote(text) + " must be in [0, 1)");
  return spread;
}

PidGains ParseGains(const std::string& text) {
  const auto v = ParseList(text, "--gains");
  if (v.size() != 3) throw BadInput("--gains " + Quote(text) + " must be three numbers KP,KI,KD");
  const PidGains g{v[0], v[1], v[2]};
  std::string error;
  if (!GainsAreValid(g, &error)) throw BadInput(error);
  return g;
}

LoopAnalysis AnalyzeOrThrow(const Plant& plant, const PidGains& gains, const LoopOptions& options) {
  LoopAnalysis a;
  std::string error;
  if (const Status st = AnalyzeLoop(plant, gains, options, LoopAnalysisOptions{}, &a); !st.ok())
    throw BadInput(st.message());
  return a;
}

std::string FormatRobustness(const LoopAnalysis& a, const LoopBounds& bounds) {
  std::ostringstream os;
  os << std::setprecision(5);
  auto at = [](double w) {
    std::ostringstream s;
    s << std::setprecision(4);
    if (std::isinf(w))
      s << " (w -> inf)";
    else if (std::isfinite(w))
      s << " at " << w << " rad/s";
    return s.str();
  };
  os << "robustness       " << ToString(a.loop) << " loop"
     << (a.loop == LoopKind::kSampled ? ", frequency response up to pi/dt" : "") << "\n";
  if (!a.stable) {
    os << "  margins        - (unstable loop)\n";
  } else {
    os << "  Ms = ||S||inf  " << a.ms << at(a.ms_rad_s) << "\n";
    os << "  Mt = ||T||inf  " << a.mt << at(a.mt_rad_s) << "\n";
    if (std::isfinite(a.gain_margin))
      os << "  gain margin    " << a.gain_margin << " (" << 20.0 * std::log10(a.gain_margin) << " dB)"
         << at(a.phase_crossover_rad_s) << "\n";
    else
      os << "  gain margin    inf (" << a.gain_margin_note << ")\n";
    if (std::isfinite(a.phase_margin_deg))
      os << "  phase margin   " << a.phase_margin_deg << " deg" << at(a.gain_crossover_rad_s)
         << ", delay margin " << a.delay_margin_s << " s\n";
    else
      os << "  phase margin   inf (" << a.phase_margin_note << ")\n";
    if (a.phase_margins_deg.size() > 1) {
      os << "  crossovers     ";
      for (std::size_t i = 0; i < a.phase_margins_deg.size(); ++i)
        os << (i ? ", " : "") << a.phase_margins_deg[i] << " deg at " << a.gain_crossovers_rad_s[i]
           << " rad/s";
      os << "   (arg L + 180 each; the phase margin is the smallest |.|)\n";
    }
    if (std::isfinite(a.noise_gain))
      os << "  noise gain     " << a.noise_gain << at(a.noise_gain_rad_s) << "   (||C S||inf)\n";
    else
      os << "  noise gain     unbounded (" << a.noise_gain_note << ")\n";
  }
  if (a.delay_s > 0.0)
    os << "  dead time      " << a.delay_s << " s, exact e^(-jwL); " << a.stability_note << "\n";
  if (a.time_constant_note.empty())
    os << "  slowest tau    " << a.slowest_time_constant_s << " s   (1 / min |Re p|)\n";
  else
    os << "  slowest tau    - (" << a.time_constant_note << ")\n";
  for (const Cancellation& c : a.cancellations)
    os << "  cancellation   pole " << FormatPoles({c.pole}) << " near controller zero "
       << FormatPoles({c.zero}) << " (" << 100.0 * c.relative_distance << " % apart)\n";
  for (const std::string& v : LoopBoundsViolations(a, bounds)) os << "  VIOLATES       " << v << "\n";
  return os.str();
}

std::string FormatPoles(const std::vector<std::complex<double>>& poles) {
  std::ostringstream os;
  os << std::setprecision(6);
  for (std::size_t i = 0; i < poles.size(); ++i) {
    if (i) os << ", ";
    os << poles[i].real();
    if (poles[i].imag() != 0.0) os << (poles[i].imag() > 0 ? "+" : "-") << std::abs(poles[i].imag()) << "j";
  }
  return os.str();
}

std::string FormatEvaluation(const Evaluation& ev) {
  std::ostringstream os;
  auto num = [](double v) {
    std::ostringstream s;
    if (std::isfinite(v))
      s << std::setprecision(6) << v;
    else
      s << "-";
    return s.str();
  };
  os << "plant            " << ev.plant.name << "  G(s) = " << ev.plant.tf.ToString() << "\n";
  os << "gains            kp = " << ev.gains.kp << ", ki = " << ev.gains.ki << ", kd = " << ev.gains.kd;
  if (ev.gains.tf > 0.0) os << ", tf = " << ev.gains.tf << " s (filtered derivative)";
  os << "\n";
  os << "loop             " << ToString(ev.options.loop);
  if (ev.options.loop == LoopKind::kSampled) os << " (dt = " << ev.options.dt_s << " s)";
  os << ", ts = " << ev.options.sample_time_s << " s, n = " << ev.options.horizon_s << " s, "
     << ev.options.NumSamples() << " samples\n";
  if (ev.options.reference != 1.0)
    os << "reference        step of A = " << ev.options.reference << " (e = A - y)\n";
  const DisturbanceOptions& d = ev.options.disturbance;
  if (d.kind == DisturbanceKind::kChirp)
    os << "disturbance      chirp +/-" << d.amplitude << ", " << d.chirp_f0_hz << " to " << d.chirp_f1_hz
       << " Hz over " << d.chirp_duration_s << " s, at the plant input\n";
  else if (d.kind != DisturbanceKind::kNone)
    os << "disturbance      " << ToString(d.kind) << " +/-" << d.amplitude << ", period " << d.period_s
       << " s, at the plant input\n";
  if (ev.options.measurement_noise.resolution != 0.0)
    os << "measured y       rounded to a multiple of " << ev.options.measurement_noise.resolution
       << ": every score is of the measured y\n";
  if (ev.options.measurement_noise.sigma != 0.0)
    os << "measured y       y + noise of std deviation " << ev.options.measurement_noise.sigma << " (seed "
       << ev.options.measurement_noise.seed << "): every score is of the measured y\n";
  os << "stable           " << (ev.stability.stable ? "yes" : "NO (objectives are +inf)") << "\n";
  if (ev.options.loop == LoopKind::kContinuous && ev.plant.delay_s > 0.0)
    os << "closed-loop poles (s) infinitely many (dead time " << ev.plant.delay_s
       << " s): stability by the crossing frequencies, the response by the method of steps\n";
  else
    os << "closed-loop poles " << (ev.options.loop == LoopKind::kSampled ? "(z) " : "(s) ")
       << FormatPoles(ev.stability.poles) << "\n";
  // The integrals of |e| in the plant's units head the scores; eq. (4)'s sum
  // of samples (which changes with the sample time) keeps its name and the
  // first place on the paper's plants (docs/tuning.md, "Any plant").
  std::ostringstream integrals, sums;
  integrals << "integral |e| dt  " << num(ev.iae_continuous) << "\n";
  if (!std::isnan(ev.load_iae_continuous))
    integrals << "load |e| dt      " << num(ev.load_iae_continuous) << "   (integral of |y|, the unit load step)\n";
  const std::vector<std::string> builtin = BuiltinPlantNames();
  const bool paper = std::find(builtin.begin(), builtin.end(), ev.plant.name) != builtin.end();
  sums << (paper ? "IAE (eq. 4)      " : "sum |e(t_k)|     ") << num(ev.iae)
       << (paper ? "" : "   (eq. 4's form: over the samples, it changes with --sample-time)") << "\n";
  if (ev.options.reference != 1.0) sums << "IAE / A          " << num(ev.iae_per_unit) << "\n";
  if (ev.options.disturbance.kind != DisturbanceKind::kNone)
    sums << "IAE undisturbed  " << num(ev.iae_undisturbed) << "\n";
  sums << (paper ? "load IAE         " : "load sum |e|     ") << num(ev.load_iae)
       << "   (unit step at the plant input, r = 0)\n";
  os << (paper ? sums.str() : integrals.str() + sums.str());
  os << "ISE              " << num(ev.ise) << "\n";
  os << "ITAE             " << num(ev.itae) << "\n";
  if (paper) os << integrals.str();
  if (ev.step.valid) {
    os << "rise time        " << num(ev.step.rise_time_s) << " s   (10-90 %, stepinfo)\n";
    os << "overshoot        " << num(ev.step.overshoot_pct) << " %\n";
    os << "settling time    " << num(ev.step.settling_time_s) << " s   (2 % band)\n";
    os << "peak             " << num(ev.step.peak) << " at " << num(ev.step.peak_time_s) << " s\n";
  } else {
    os << "step metrics     - (" << ev.step.note << ")\n";
  }
  if (ev.has_motor) {
    os << "motor            " << (ev.lost_steps ? ev.motor_note : "no steps lost") << "\n";
    os << "peak phase       " << num(ev.motor.phase_voltage_v) << " V, " << num(ev.motor.phase_current_a)
       << " A; peak load angle " << num(ev.motor.load_angle_rad) << " rad (electrical)\n";
  }
  return os.str();
}

void WriteSamplesCsv(const Evaluation& ev, const evaluation::CommandSeries& series, const std::string& path) {
  std::ostringstream f;
  f << std::setprecision(17) << "t,r,y,e,n,u,y_load,u_load\n";
  // A column the loop has none of (the nonlinear motor's load response) is empty.
  const auto cell = [](const std::vector<double>& v, std::size_t m) {
    std::ostringstream c;
    c << std::setprecision(17);
    if (m < v.size()) c << v[m];
    return c.str();
  };
  for (std::size_t m = 0; m < ev.y.size(); ++m)
    f << ev.t[m] << "," << ev.options.reference << "," << ev.y[m] << "," << ev.options.reference - ev.y[m]
      << "," << ev.n[m] << "," << cell(series.u, m) << "," << cell(series.load_y, m) << ","
      << cell(series.load_u, m) << "\n";
  WriteOutputFile(path, f.str());
}

std::string ReadInputFile(const std::string& path, const std::string& flag, std::size_t max_bytes) {
  std::string text;
  Status s = io::ReadFile(path, max_bytes, &text);
  if (!s.ok()) Require(Status(s.code(), flag + " " + s.message()));
  return text;
}

void WriteOutputFile(const std::string& path, const std::string& text) { Require(io::WriteFile(path, text)); }

}  // namespace pidlab::cli
