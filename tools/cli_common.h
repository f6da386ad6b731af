#pragma once
// Shared pieces of the `pidlab` command line: flag groups, parsing of lists,
// JSON output of an evaluation, and the bad-input exit convention
// (one line on stderr naming the value, exit status 2).

#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"
#include "pidlab/episode_client/episode_client.h"
#include "pidlab/episode_client/episode_pool.h"
#include "pidlab/evaluation/command_series.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/io/files.h"
#include "pidlab/results/replay_json.h"
#include "pidlab/results/results_json.h"
#include "pidlab/spec/field.h"
#include "pidlab/spec/status.h"

namespace pidlab::cli {

/// Thrown for bad user input; main prints "pidlab <cmd>: error: <what>" and exits 2.
/// Bad input is anything the user typed, an output path that cannot be
/// written included; a runtime failure (LCM, gnuplot, a full disk) exits 1.
struct BadInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Every number typed on the command line is finite and at most this in
/// magnitude (README.md, "Exit status and limits").
using spec::kMaxInputMagnitude;
/// The most points `plot` draws over all its curves, and the most rows of
/// `evaluate --trajectory-csv` (every step is kept in memory first).
inline constexpr long kMaxRecordedPoints = 10000000;
// How every error message echoes a user's value (pidlab/spec/field.h).
using spec::kMaxEchoedChars;
using spec::Quote;
using spec::Truncate;

/// CLI11 check of a floating-point flag: a finite number of magnitude at most
/// kMaxInputMagnitude.
CLI::Validator FiniteNumber();
/// The same, or +/-inf where infinity means "none" (tune --max-overshoot).
CLI::Validator NumberOrInfinity();
/// CLI11 check of an unsigned flag (--seed): digits only, so "-1" is refused
/// instead of wrapping around to 2^64 - 1.
CLI::Validator WholeNumber();

/// Bad input unless `path` can be opened for writing (created if absent, then
/// removed again; an existing file is left as it is). Run before any work.
void CheckOutputFile(const std::string& path, const std::string& flag);
/// The most a spec, a model file or a result file (--spec, --model,
/// --from) may hold.
inline constexpr std::size_t kMaxSpecFileBytes = 1 << 20;
/// The whole of the file `path` named by `flag`, at most `max_bytes`; bad
/// input otherwise ("--from 'x.json' cannot be read: No such file or directory").
std::string ReadInputFile(const std::string& path, const std::string& flag, std::size_t max_bytes);
/// `text` into `path`, whole or not at all (io::WriteFile): a full disk is a
/// runtime failure naming the path and the errno's words; the old file stays.
void WriteOutputFile(const std::string& path, const std::string& text);
/// Creates the folder `dir` if needed; bad input unless a file can be written in it.
void PrepareOutputDir(const std::string& dir, const std::string& flag);

/// A flag's value, else the environment variable's (what `pidlab launch`
/// exports to its COMMAND), else the fallback.
std::string FromEnv(const std::string& flag, const char* env, const char* fallback);

/// The notes of a run over the trio (an episode run again, a trio left
/// out). Counted and said in one short line by FlushRunNotes (before the
/// command's last line); each in full as it comes with `verbose`; none with
/// `quiet`. Thread-safe: the starts of a tuning note from several threads.
void SetRunNoteMode(bool quiet, bool verbose);
void AddRunNote(const std::string& note);
/// "pidlab: note: 3 episodes run again, 1 trio left out (-v shows each)", once.
void FlushRunNotes();

/// --lcm-url, --channel-prefix, --episode-timeout, --silence-deadline,
/// --max-attempts and --auth-key of the LCM backend.
struct LcmFlags {
  std::string lcm_url, channel_prefix, auth_key_file;
  double episode_timeout_s = 600.0;
  double silence_deadline_s = transport::RecoveryOptions{}.silence_deadline_s;
  int max_attempts = episode_client::EpisodeClientOptions{}.max_attempts;
  bool quiet = false, verbose = false;  // --quiet, -v: the notes of the run (SetRunNoteMode)
  void Register(CLI::App* app);
  /// An episode client on the trio these flags (or $PIDLAB_LCM_URL,
  /// $PIDLAB_CHANNEL_PREFIX and $PIDLAB_AUTH_KEY_FILE) name. Throws BadInput for bad flags,
  /// std::runtime_error if LCM cannot start.
  std::unique_ptr<episode_client::EpisodeClient> MakeClient() const;
  /// The trios of tune: --lcm-url (comma-separated URLs), else
  /// $PIDLAB_LCM_URLS (pidlab launch --trios K), else $PIDLAB_LCM_URL.
  std::unique_ptr<episode_client::EpisodePool> MakePool() const;
  /// The first URL of --lcm-url, else $PIDLAB_LCM_URL, else LCM's.
  std::string Url() const;
  episode_client::EpisodeClientOptions ClientOptions(const std::string& url) const;
};

/// Strict number parsing: the whole string must be a number, finite and at
/// most kMaxInputMagnitude in magnitude (or +/-inf if `allow_infinite`).
double ParseDouble(const std::string& text, const std::string& what, bool allow_infinite = false);
/// "a,b,c" -> {a, b, c}; throws BadInput naming `what`.
std::vector<double> ParseList(const std::string& text, const std::string& what, bool allow_infinite = false);
PidGains ParseGains(const std::string& text);
/// A relative spread "10%" or "0.1" of `flag`, in [0, 1); throws BadInput.
double ParseSpread(const std::string& text, const std::string& flag);

/// The analysis as table rows (evaluate, tune).
std::string FormatRobustness(const analysis::LoopAnalysis& a, const analysis::LoopBounds& bounds);
/// Throws BadInput(error) unless `ok`: a spec that does not build.
inline void Require(bool ok, const std::string& error) {
  if (!ok) throw BadInput(error);
}
/// The exit convention in one place: a library's Status as the command
/// line's failure. kInvalidInput is bad input (exit 2); a failed runner or
/// anything else is a runtime failure (exit 1).
inline void Require(const Status& status) {
  if (status.ok()) return;
  if (status.code() == StatusCode::kInvalidInput) throw BadInput(status.message());
  throw std::runtime_error(status.message());
}
/// AnalyzeLoop with the default options; throws BadInput on its error.
analysis::LoopAnalysis AnalyzeOrThrow(const Plant& plant, const PidGains& gains,
                                      const evaluation::LoopOptions& options);

// JsonNumber (null for NaN/inf), ToJson(Evaluation), ToJson(PidGains): the
// JSON objects live in a library the Python module shares (results/).
using results::JsonNumber;
using results::RealtimeJson;
using results::RobustnessJson;
using results::ToJson;
std::string FormatPoles(const std::vector<std::complex<double>>& poles);
/// Human-readable report of one evaluation.
std::string FormatEvaluation(const evaluation::Evaluation& ev);
/// CSV of the sample times: t,r,y,e,n and the command and load response,
/// u,y_load,u_load (evaluation::CommandAndLoadSeries; empty cells where the loop
/// has none). BadInput if `path` cannot be opened.
void WriteSamplesCsv(const evaluation::Evaluation& ev, const evaluation::CommandSeries& series,
                     const std::string& path);

}  // namespace pidlab::cli
