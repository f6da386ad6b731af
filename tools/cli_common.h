#pragma once
// Shared pieces of the `pidlab` command line: flag groups, parsing of lists,
// JSON output of an evaluation, and the bad-input exit convention
// (one line on stderr naming the value, exit status 2).

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/tuner/episode_client.h"
#include "pidlab/tuner/evaluation.h"

namespace pidlab::cli {

/// Thrown for bad user input; main prints "pidlab <cmd>: error: <what>" and exits 2.
struct BadInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A flag's value, else the environment variable's (what `pidlab launch`
/// exports to its COMMAND), else the fallback.
std::string FromEnv(const std::string& flag, const char* env, const char* fallback);

/// --lcm-url, --channel-prefix, --episode-timeout, --silence-deadline,
/// --max-attempts and --auth-key of the LCM backend.
struct LcmFlags {
  std::string lcm_url, channel_prefix, auth_key_file;
  double episode_timeout_s = 600.0;
  double silence_deadline_s = transport::RecoveryOptions{}.silence_deadline_s;
  int max_attempts = EpisodeClientOptions{}.max_attempts;
  void Register(CLI::App* app);
  /// An episode client on the trio these flags (or $PIDLAB_LCM_URL,
  /// $PIDLAB_CHANNEL_PREFIX and $PIDLAB_AUTH_KEY_FILE) name. Throws BadInput for bad flags,
  /// std::runtime_error if LCM cannot start.
  std::unique_ptr<EpisodeClient> MakeClient() const;
};

/// Strict number parsing: the whole string must be a finite-or-not double.
double ParseDouble(const std::string& text, const std::string& what);
/// "a,b,c" -> {a, b, c}; throws BadInput naming `what`.
std::vector<double> ParseList(const std::string& text, const std::string& what);
PidGains ParseGains(const std::string& text);

/// --plant / --num / --den / --stepper NAME=VALUE.
struct PlantFlags {
  std::string plant;
  std::string num, den;
  std::vector<std::string> stepper_overrides;
  void Register(CLI::App* app, bool required = true);
  Plant Build() const;  // throws BadInput
};

/// --loop, --dt, --sample-time, --horizon, disturbance and discrete PID flags.
struct LoopFlags {
  std::string loop = "continuous";
  double dt_s = 1e-3, sample_time_s = 0.05, horizon_s = 25.0, stability_margin = 1e-9;
  std::string disturbance;  // empty: square if an amplitude is given
  double disturbance_amplitude = 0.0, disturbance_period_s = 2.0, disturbance_phase_s = 0.0;
  double disturbance_step_time_s = 0.0, noise_hold_s = 0.01;
  std::uint64_t seed = 1;
  double derivative_filter_s = 0.0;
  std::string output_limits, anti_windup = "clamping", derivative_on = "error", integral = "backward-euler";
  void Register(CLI::App* app);
  LoopOptions Build() const;  // throws BadInput
};

nlohmann::json JsonNumber(double v);  // null for NaN/inf
nlohmann::json ToJson(const Evaluation& ev);
nlohmann::json ToJson(const PidGains& g);
std::string FormatPoles(const std::vector<std::complex<double>>& poles);
/// Human-readable report of one evaluation.
std::string FormatEvaluation(const Evaluation& ev);
/// CSV of the sample times: t,r,y,e,n.
void WriteSamplesCsv(const Evaluation& ev, const std::string& path);

}  // namespace pidlab::cli
