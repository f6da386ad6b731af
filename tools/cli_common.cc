#include "cli_common.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "pidlab/transport/wire.h"

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

std::string Truncate(const std::string& text, std::size_t max_chars) {
  const std::string marker = "...(" + std::to_string(text.size()) + " chars)";
  const std::size_t keep = max_chars > marker.size() ? max_chars - marker.size() : 0;
  std::string out;
  std::size_t head = 0;  // the longest prefix of whole pieces that leaves room for the marker
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
    if (out.size() <= keep) head = out.size();
    if (out.size() > max_chars) return out.substr(0, head) + marker;
  }
  return out;
}

std::string Quote(const std::string& text) { return "'" + Truncate(text) + "'"; }

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

void LcmFlags::Register(CLI::App* app) {
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
  return std::make_unique<EpisodeClient>(ClientOptions(Url()));  // throws runtime_error: exit 1
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
  return std::make_unique<EpisodePool>(trios);  // throws runtime_error: exit 1
}

EpisodeClientOptions LcmFlags::ClientOptions(const std::string& url) const {
  EpisodeClientOptions co;
  co.lcm_url = url;
  co.transport.channel_prefix =
      FromEnv(channel_prefix, "PIDLAB_CHANNEL_PREFIX", transport::kDefaultChannelPrefix);
  co.episode_timeout_s = episode_timeout_s;
  co.recovery.silence_deadline_s = silence_deadline_s;
  co.max_attempts = max_attempts;
  co.on_note = [](const std::string& note) { std::cerr << "pidlab: note: " << note << "\n"; };
  std::string error;
  const std::string key_file = FromEnv(auth_key_file, transport::kAuthKeyFileEnv, "");
  if (!key_file.empty()) {
    transport::AuthKey key;
    if (!transport::LoadAuthKey(key_file, &key, &error)) throw BadInput(error);
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

void PlantFlags::Register(CLI::App* app, bool required) {
  auto* opt =
      app->add_option("--plant", plant,
                      "double_integrator (alias linear) = 1/s^2, oscillator (alias nonlinear) = "
                      "1/(s^2+1), stepper_motor (alias stepper) = eq. (3), stepper_nonlinear = the nonlinear "
                      "PM stepper (sampled loop; docs/stepper.md), or custom with --num/--den");
  (void)required;
  app->add_option("--num", num, "custom plant numerator, descending powers of s, e.g. 1");
  app->add_option("--den", den, "custom plant denominator, descending powers of s, e.g. 1,0,0");
  app->add_option("--stepper", stepper_overrides,
                  "override a Table I parameter, NAME=VALUE (resistance_ohm, self_inductance_h, "
                  "mutual_inductance_h, inertia_kg_m2, rotor_teeth, viscous_friction, tooth_pitch_rad, "
                  "stationary_current_a, flux_linkage); repeatable")
      ->take_all();
  app->add_option("--detent-torque", detent_torque_nm,
                  "stepper_nonlinear: detent torque amplitude T_d in N m (T_d sin(4 N_r theta))")
      ->check(FiniteNumber());
  app->add_option("--load-torque", load_torque_nm, "stepper_nonlinear: constant load torque in N m")
      ->check(FiniteNumber());
  app->add_option("--load-step", load_step_nm,
                  "stepper_nonlinear: a further load torque step in N m at --load-step-time")
      ->check(FiniteNumber());
  app->add_option("--load-step-time", load_step_time_s, "stepper_nonlinear: time of the load step in s")
      ->check(FiniteNumber());
  app->add_option("--voltage-limit", voltage_limit_v,
                  "stepper_nonlinear: phase-voltage limit of the drive in V (default: none)")
      ->check(NumberOrInfinity());
  app->add_option("--input-scale", input_scale,
                  "stepper_nonlinear: g in phi = theta0 + g u; 0 (default) = (L-M)/L, which makes the "
                  "linearisation eq. (3); 1 = the physical angle command")
      ->check(FiniteNumber());
  app->add_option("--drive", drive,
                  "stepper_nonlinear: linear (phase voltages proportional to u, default) or microstep (sine "
                  "table at phi = theta0 + g u, wraps every electrical period)");
  opt->check([](const std::string&) { return std::string(); });
}

NonlinearStepperOptions PlantFlags::NonlinearOptions() const {
  NonlinearStepperOptions o;
  o.motor = StepperParameters();
  o.detent_torque_nm = detent_torque_nm;
  o.load_torque_nm = load_torque_nm;
  o.load_step_nm = load_step_nm;
  o.load_step_time_s = load_step_time_s;
  o.voltage_limit_v = voltage_limit_v;
  o.input_scale = input_scale;
  if (drive != "linear" && drive != "microstep")
    throw BadInput("--drive " + Quote(drive) + " must be linear or microstep");
  o.microstep_table = drive == "microstep";
  std::string error;
  if (!o.IsValid(&error)) throw BadInput(error);
  return o;
}

Plant PlantFlags::Build() const {
  std::string error;
  Plant p;
  const bool custom = !num.empty() || !den.empty();
  if (custom && !plant.empty() && plant != "custom")
    throw BadInput("--plant " + Quote(plant) +
                   " cannot be combined with --num/--den (use --plant custom or omit it)");
  if (custom) {
    if (num.empty() || den.empty()) throw BadInput("a custom plant needs both --num and --den");
    if (!MakeCustomPlant(ParseList(num, "--num"), ParseList(den, "--den"), &p, &error)) throw BadInput(error);
    return p;
  }
  if (plant.empty()) throw BadInput("--plant is required (or --num and --den for a custom plant)");
  if (plant == "custom") throw BadInput("--plant custom needs --num and --den");
  const bool nonlinear = plant == "stepper_nonlinear";
  const NonlinearStepperOptions defaults;
  if (!nonlinear &&
      (detent_torque_nm != 0.0 || load_torque_nm != 0.0 || load_step_nm != 0.0 || load_step_time_s != 0.0 ||
       voltage_limit_v != defaults.voltage_limit_v || input_scale != 0.0 || drive != "linear"))
    throw BadInput(
        "--detent-torque, --load-torque, --load-step, --load-step-time, --voltage-limit, --input-scale and "
        "--drive apply "
        "only to --plant stepper_nonlinear, not " +
        Quote(plant));
  if (nonlinear) {
    if (!MakeNonlinearStepperPlant(NonlinearOptions(), &p, &error)) throw BadInput(error);
    return p;
  }
  const StepperMotorParameters sp = StepperParameters();
  // A plant name is printable and short, so Truncate leaves every valid one
  // as it is, and MakePlant's "unknown plant '...'" echoes at most 200 chars.
  if (!MakePlant(Truncate(plant), sp, &p, &error)) throw BadInput(error);
  return p;
}

StepperMotorParameters PlantFlags::StepperParameters() const {
  StepperMotorParameters sp;
  for (const auto& kv : stepper_overrides) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw BadInput("--stepper " + Quote(kv) + " must be NAME=VALUE");
    const std::string name = kv.substr(0, eq);
    double* field = nullptr;
    if (name == "resistance_ohm")
      field = &sp.resistance_ohm;
    else if (name == "self_inductance_h")
      field = &sp.self_inductance_h;
    else if (name == "mutual_inductance_h")
      field = &sp.mutual_inductance_h;
    else if (name == "inertia_kg_m2")
      field = &sp.inertia_kg_m2;
    else if (name == "rotor_teeth")
      field = &sp.rotor_teeth;
    else if (name == "viscous_friction")
      field = &sp.viscous_friction;
    else if (name == "tooth_pitch_rad")
      field = &sp.tooth_pitch_rad;
    else if (name == "stationary_current_a")
      field = &sp.stationary_current_a;
    else if (name == "flux_linkage")
      field = &sp.flux_linkage;
    else
      throw BadInput("--stepper parameter " + Quote(name) + " is unknown");
    *field = ParseDouble(kv.substr(eq + 1), "--stepper " + name);
  }
  if (!stepper_overrides.empty() && plant != "stepper_motor" && plant != "stepper" &&
      plant != "stepper_nonlinear")
    throw BadInput("--stepper overrides apply only to --plant stepper_motor or stepper_nonlinear, not " +
                   Quote(plant));
  std::string error;
  if (!sp.IsValid(&error)) throw BadInput(error);
  return sp;
}

void LoopFlags::Register(CLI::App* app) {
  app->add_option("--loop", loop,
                  "continuous (exact, ideal PID) or sampled (discrete PID at --dt, ZOH plant)")
      ->capture_default_str();
  app->add_option("--dt", dt_s, "sampled-loop period in s; --sample-time must be a multiple")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--sample-time", sample_time_s, "ts of eq. (4): spacing of the error samples in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--horizon", horizon_s, "n of eq. (4): last sample time in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--reference", reference,
                  "size A of the reference step r(t) = A (1 = the paper's unit step); e = A - y in every "
                  "objective, step metrics relative to the final value")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--stability-margin", stability_margin,
                  "strict stability: Re p < -margin*max(1,|p|), p = s-plane pole (sampled: p = log(z)/dt)")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option(
      "--disturbance", disturbance,
      "none|square|step|sine|noise at the plant input (default: square if an amplitude is given)");
  app->add_option("--disturbance-amplitude", disturbance_amplitude,
                  "square +/-A, step height, sine peak or noise std deviation")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--disturbance-period", disturbance_period_s, "square/sine period in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--disturbance-phase", disturbance_phase_s, "time shift of the disturbance in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--disturbance-step-time", disturbance_step_time_s, "step disturbance time in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--noise-hold", noise_hold_s, "noise is held constant over this interval in s")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--seed", seed, "seed of the noise disturbance (and of the search, for tune)")
      ->check(WholeNumber())
      ->capture_default_str();
  app->add_option("--derivative-filter", derivative_filter_s,
                  "derivative filter time constant Tf in s, both loops: C(s) = kp + ki/s + kd s/(Tf s + 1); "
                  "0 = the paper's ideal PID")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--derivative-filter-ratio", derivative_filter_ratio,
                  "derivative filter by a ratio N: Tf = kd / (N kp) (Td / N), both loops; 0 = not used; "
                  "excludes --derivative-filter")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--output-limits", output_limits, "sampled PID: output limits LO,HI");
  app->add_option("--anti-windup", anti_windup, "sampled PID: none|clamping|back-calculation")
      ->capture_default_str();
  app->add_option("--derivative-on", derivative_on, "sampled PID: error|measurement")->capture_default_str();
  app->add_option("--integral", integral, "sampled PID: backward-euler|forward-euler|trapezoidal")
      ->capture_default_str();
}

LoopOptions LoopFlags::Build() const {
  LoopOptions o;
  if (!ParseLoopKind(loop, &o.loop))
    throw BadInput("--loop " + Quote(loop) + " must be continuous or sampled");
  o.dt_s = dt_s;
  o.sample_time_s = sample_time_s;
  o.horizon_s = horizon_s;
  o.stability_margin = stability_margin;
  o.reference = reference;
  DisturbanceOptions& d = o.disturbance;
  if (disturbance.empty()) {
    d.kind = disturbance_amplitude != 0.0 ? DisturbanceKind::kSquare : DisturbanceKind::kNone;
  } else if (!ParseDisturbanceKind(disturbance, &d.kind)) {
    throw BadInput("--disturbance " + Quote(disturbance) + " must be none, square, step, sine or noise");
  }
  d.amplitude = disturbance_amplitude;
  d.period_s = disturbance_period_s;
  d.phase_s = disturbance_phase_s;
  d.step_time_s = disturbance_step_time_s;
  d.noise_hold_s = noise_hold_s;
  d.seed = seed;
  o.pid.dt_s = dt_s;
  o.pid.derivative_filter_s = derivative_filter_s;
  o.derivative_filter_ratio = derivative_filter_ratio;
  if (!output_limits.empty()) {
    const auto v = ParseList(output_limits, "--output-limits", /*allow_infinite=*/true);  // inf: no limit
    if (v.size() != 2) throw BadInput("--output-limits " + Quote(output_limits) + " must be LO,HI");
    o.pid.output_min = v[0];
    o.pid.output_max = v[1];
  }
  if (!ParseAntiWindup(anti_windup, &o.pid.anti_windup))
    throw BadInput("--anti-windup " + Quote(anti_windup) + " must be none, clamping or back-calculation");
  if (!ParseDerivativeOn(derivative_on, &o.pid.derivative_on))
    throw BadInput("--derivative-on " + Quote(derivative_on) + " must be error or measurement");
  if (!ParseIntegralMethod(integral, &o.pid.integral))
    throw BadInput("--integral " + Quote(integral) + " must be backward-euler, forward-euler or trapezoidal");
  std::string error;
  if (!o.IsValid(&error)) throw BadInput(error);
  return o;
}

void BoundsFlags::Register(CLI::App* app, const std::string& what) {
  app->add_option("--max-ms", max_ms, what + " with Ms = ||S||inf above this (e.g. 1.6)")
      ->check(NumberOrInfinity());
  app->add_option("--max-mt", max_mt, what + " with Mt = ||T||inf above this (e.g. 1.3)")
      ->check(NumberOrInfinity());
  app->add_option("--max-noise-gain", max_noise_gain,
                  what + " with the noise gain ||C S||inf above this (the ideal derivative's is unbounded)")
      ->check(NumberOrInfinity());
  app->add_option("--min-phase-margin", min_phase_margin_deg, what + " with a phase margin below this (deg)")
      ->check(FiniteNumber());
  app->add_option("--min-gain-margin", min_gain_margin,
                  what + " with a gain margin within this factor of 1 (> 1, e.g. 2 = 6 dB; 0 = none)")
      ->check(FiniteNumber());
  app->add_option("--max-time-constant", max_time_constant_s,
                  what + " whose slowest closed-loop time constant 1/min|Re p| exceeds this (s)")
      ->check(NumberOrInfinity());
}

LoopBounds BoundsFlags::Build() const {
  LoopBounds b;
  b.max_ms = max_ms;
  b.max_mt = max_mt;
  b.max_noise_gain = max_noise_gain;
  b.min_phase_margin_deg = min_phase_margin_deg;
  b.min_gain_margin = min_gain_margin;
  b.max_time_constant_s = max_time_constant_s;
  std::string error;
  if (!b.IsValid(&error)) throw BadInput(error);
  return b;
}

LoopAnalysis AnalyzeOrThrow(const Plant& plant, const PidGains& gains, const LoopOptions& options) {
  LoopAnalysis a;
  std::string error;
  if (!AnalyzeLoop(plant, gains, options, LoopAnalysisOptions{}, &a, &error)) throw BadInput(error);
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
    if (std::isfinite(a.noise_gain))
      os << "  noise gain     " << a.noise_gain << at(a.noise_gain_rad_s) << "   (||C S||inf)\n";
    else
      os << "  noise gain     unbounded (" << a.noise_gain_note << ")\n";
  }
  os << "  slowest tau    " << a.slowest_time_constant_s << " s   (1 / min |Re p|)\n";
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
  if (ev.options.disturbance.kind != DisturbanceKind::kNone)
    os << "disturbance      " << ToString(ev.options.disturbance.kind) << " +/-"
       << ev.options.disturbance.amplitude << ", period " << ev.options.disturbance.period_s
       << " s, at the plant input\n";
  os << "stable           " << (ev.stability.stable ? "yes" : "NO (objectives are +inf)") << "\n";
  os << "closed-loop poles " << (ev.options.loop == LoopKind::kSampled ? "(z) " : "(s) ")
     << FormatPoles(ev.stability.poles) << "\n";
  os << "IAE (eq. 4)      " << num(ev.iae) << "\n";
  if (ev.options.reference != 1.0) os << "IAE / A          " << num(ev.iae_per_unit) << "\n";
  if (ev.options.disturbance.kind != DisturbanceKind::kNone)
    os << "IAE undisturbed  " << num(ev.iae_undisturbed) << "\n";
  os << "load IAE         " << num(ev.load_iae) << "   (unit step at the plant input, r = 0)\n";
  os << "ISE              " << num(ev.ise) << "\n";
  os << "ITAE             " << num(ev.itae) << "\n";
  os << "integral |e| dt  " << num(ev.iae_continuous) << "\n";
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

void WriteSamplesCsv(const Evaluation& ev, const std::string& path) {
  std::ofstream f(path);
  if (!f) throw BadInput("--samples-csv " + Quote(path) + " cannot be written");
  f << std::setprecision(17) << "t,r,y,e,n\n";
  for (std::size_t m = 0; m < ev.y.size(); ++m)
    f << ev.t[m] << "," << ev.options.reference << "," << ev.y[m] << "," << ev.options.reference - ev.y[m]
      << "," << ev.n[m] << "\n";
  f.close();
  if (!f) throw std::runtime_error("writing " + path + " failed");
}

nlohmann::json RealtimeJson(const transport::RealtimeStats& s) {
  return {{"missed_deadlines", s.missed_deadlines},
          {"lateness_p50_s", JsonNumber(s.lateness_p50_s)},
          {"lateness_p99_s", JsonNumber(s.lateness_p99_s)},
          {"lateness_max_s", JsonNumber(s.lateness_max_s)},
          {"rate_hz", JsonNumber(s.rate_hz)}};
}

}  // namespace pidlab::cli
