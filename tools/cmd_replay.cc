// pidlab replay: read an LCM log of the trio, list its episodes, recompute
// their metrics with the code of `pidlab evaluate`, and optionally re-drive a
// fresh controller with the logged plant outputs.

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/replay/replay.h"
#include "pidlab/results/replay_json.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/transport.h"

using pidlab::evaluation::Evaluation;

namespace pidlab::cli {
namespace {

std::string Full(double v) {
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}

// Text of the table that came from the log (channel prefixes and names in the
// notes, a configuration's strings, a summary's message) with its control
// characters escaped: a log can send no escape sequence to the terminal and
// forge no table line. The JSON output escapes them itself.
std::string FromLog(const std::string& text) { return Truncate(text, std::string::npos); }

struct ReplayCommand {
  std::string log_path;
  std::vector<long> episodes;
  std::string channel_prefix;
  std::string auth_key_file;
  bool json = false;
  std::string csv;
  bool redrive = false;
  std::string backend = "local", lcm_url, lcm_prefix;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Read an LCM log of pidlab traffic (lcm-logger, 'pidlab launch --log'): list every episode with its "
        "plant, gains, steps, IAE and completeness (gaps, duplicates, out-of-order events), recomputing the "
        "metrics with the code of 'pidlab evaluate'. Foreign channels, other prefixes, self-test events, "
        "unknown "
        "types and a cut-off or corrupt tail are reported and skipped. --redrive checks that a fresh "
        "controller "
        "reproduces every logged command bit for bit.");
    app->add_option("log", log_path, "the LCM log file")->required();
    app->add_option("--episode", episodes, "only these episode ids (repeatable)")->take_all();
    app->add_option("--channel-prefix", channel_prefix, "only this channel prefix (default: every prefix)");
    app->add_flag("--json", json, "print one JSON object instead of the table");
    app->add_option("--auth-key", auth_key_file,
                    "the trio's key (default $PIDLAB_AUTH_KEY_FILE): use only messages whose tag verifies");
    app->add_option("--csv", csv, "write episode,k,t,r,y,u,n,e of the selected episodes to this CSV file");
    app->add_flag(
        "--redrive", redrive,
        "feed the logged plant outputs to a fresh DiscretePid and compare every command bit for bit "
        "(exit 1 on a mismatch)");
    app->add_option("--backend", backend,
                    "--redrive in process (local) or against a live pidlab-controller started alone (lcm)")
        ->check(CLI::IsMember({"local", "lcm"}))
        ->capture_default_str();
    app->add_option("--lcm-url", lcm_url,
                    "with --backend lcm: LCM URL (default $PIDLAB_LCM_URL, else pidlab's)");
    app->add_option(
        "--lcm-channel-prefix", lcm_prefix,
        "with --backend lcm: channel prefix of the controller (default $PIDLAB_CHANNEL_PREFIX, else "
        "PIDLAB_)");
    return [this] { return Run(); };
  }

  std::string Url() const { return FromEnv(lcm_url, "PIDLAB_LCM_URL", transport::kDefaultLcmUrl); }
  std::string Prefix() const {
    return FromEnv(lcm_prefix, "PIDLAB_CHANNEL_PREFIX", transport::kDefaultChannelPrefix);
  }

  replay::RedriveResult RedriveLive(const replay::Episode& e) const {
    replay::RedriveResult r;
    const Status st = replay::RedriveOverLcm(e, Url(), Prefix(), 2.0, &r);
    if (st.code() == StatusCode::kInvalidInput) throw BadInput("--lcm-url: " + st.message());
    if (!st.ok()) throw std::runtime_error(st.message());
    return r;
  }

  int Run() {
    if (!csv.empty()) CheckOutputFile(csv, "--csv");  // before reading the log
    if (backend == "lcm" && !redrive) throw BadInput("--backend lcm applies to --redrive only");
    const replay::LogContents log = ReadTheLog();
    const std::vector<const replay::Episode*> selected = SelectEpisodes(log);
    std::unique_ptr<io::AtomicFile> csv_file;
    if (!csv.empty()) OpenCsv(&csv_file);
    nlohmann::json out = results::LogJson(log, log_path);
    std::ostringstream table;
    TableHeader(log, &table);
    std::vector<std::string> failed;  // --redrive: "episode ID: why", one per episode that did not reproduce
    for (const replay::Episode* e : selected) {
      ReportEpisode(*e, &out["episodes"], &table, &failed);
      if (csv_file) WriteCsv(*e, csv_file.get());
    }
    if (csv_file) Require(csv_file->Commit());  // whole, or the old file stays
    if (selected.empty()) table << "(no episode in the log)\n";
    if (json) {
      // Channel names and texts come from the log: bytes that are not UTF-8
      // are replaced (U+FFFD) rather than making the dump throw.
      std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    } else {
      std::cout << table.str();
    }
    if (!failed.empty()) {
      std::cout.flush();
      // One line on stderr: how many, and the first one's reason.
      throw std::runtime_error("--redrive: " + std::to_string(failed.size()) + " of " +
                               std::to_string(redriven_) + " episodes did not reproduce; " + failed.front());
    }
    return 0;
  }

  replay::LogContents ReadTheLog() const {
    replay::ReadOptions options;
    options.channel_prefix = channel_prefix;
    const std::string key_file = FromEnv(auth_key_file, transport::kAuthKeyFileEnv, "");
    if (!key_file.empty()) {
      transport::AuthKey key;
      std::string why;
      if (const Status st = transport::LoadAuthKey(key_file, &key); !st.ok()) throw BadInput(st.message());
      options.auth_key = key;
    }
    replay::LogContents log;
    if (const Status st = replay::ReadLog(log_path, options, &log); !st.ok()) {
      // A file that opened but holds no LCM event, an empty one included, is
      // damaged content (exit 1), not a path the user mistyped (exit 2).
      if (log.opened) throw std::runtime_error(st.message());
      throw BadInput(st.message());
    }
    return log;
  }

  // The episodes of --episode (all without it); an id not in the log is bad input.
  std::vector<const replay::Episode*> SelectEpisodes(const replay::LogContents& log) const {
    std::vector<const replay::Episode*> selected;
    for (const auto& e : log.episodes) {
      if (episodes.empty() || std::find(episodes.begin(), episodes.end(), e.episode_id) != episodes.end())
        selected.push_back(&e);
    }
    for (long id : episodes) {
      bool found = false;
      for (const auto* e : selected) found = found || e->episode_id == id;
      if (!found) throw BadInput("--episode " + std::to_string(id) + " is not in " + Quote(log_path));
    }
    return selected;
  }

  // ---- Table output

  void TableHeader(const replay::LogContents& log, std::ostream* table) const {
    *table << "log " << log_path << ": " << log.events << " events, " << log.pidlab_messages
           << " pidlab messages, " << (log.clean_end ? "read to the end" : "NOT read cleanly to the end")
           << " (" << log.file_bytes << " bytes)\n";
    for (const auto& n : log.notes) *table << "note: " << FromLog(n) << "\n";
    *table << std::left << std::setw(21) << "episode" << std::setw(10) << "prefix" << std::setw(19) << "plant"
           << std::setw(26) << "gains kp,ki,kd" << std::setw(8) << "steps" << std::setw(24) << "IAE"
           << "log\n";
  }

  static void TableRow(const replay::Episode& e, const std::string& iae, std::ostream* table) {
    std::string plant = "?", gains = "?";
    if (e.has_config) {
      plant = FromLog(e.spec.plant.name);
      std::ostringstream g;
      g << std::setprecision(6) << e.spec.gains.kp << "," << e.spec.gains.ki << "," << e.spec.gains.kd;
      gains = g.str();
    }
    *table << std::left << std::setw(21) << e.episode_id << std::setw(10)
           << (e.prefix.empty() ? "-" : FromLog(e.prefix)) << std::setw(19) << plant << std::setw(26) << gains
           << std::setw(8) << e.total_steps << std::setw(24) << iae
           << (e.Complete() ? "complete" : "INCOMPLETE: " + FromLog(e.CompletenessNote())) << "\n";
  }

  // One line per stream with anything besides clean arrivals.
  static void StreamDetails(const char* what, const replay::StreamStats& s, std::ostream* details) {
    if (!(s.duplicates || s.conflicts || s.out_of_order || s.beyond_end || s.filled_from_chunks)) return;
    *details << "    " << what << ": " << s.received << "/" << s.expected << " received";
    if (s.duplicates) *details << ", " << s.duplicates << " duplicates (retransmissions)";
    if (s.conflicts) *details << ", " << s.conflicts << " CONFLICTING duplicates (first kept)";
    if (s.out_of_order) *details << ", " << s.out_of_order << " out of order";
    if (s.beyond_end) *details << ", " << s.beyond_end << " outside 0..total_steps";
    if (s.filled_from_chunks) *details << ", " << s.filled_from_chunks << " filled from trajectory chunks";
    *details << "\n";
  }

  // ---- One episode: evaluation, table row and details, JSON, redrive

  // Appends the episode's JSON to *episodes_json and its lines to *table;
  // with --redrive, a line to *failed if it did not reproduce.
  void ReportEpisode(const replay::Episode& e, nlohmann::json* episodes_json, std::ostream* table,
                     std::vector<std::string>* failed) {
    Evaluation ev;
    bool evaluated = false;
    nlohmann::json j = results::EvaluatedEpisodeJson(e, &ev, &evaluated);
    const std::string why = evaluated ? "" : j["evaluation_error"].get<std::string>();
    TableRow(e, evaluated ? Full(ev.iae) : e.has_config && e.spec.relay ? "relay autotune" : "-", table);
    StreamDetails("plant outputs", e.outputs, table);
    StreamDetails("commands", e.commands, table);
    StreamDetails("disturbance samples", e.disturbances, table);
    if (e.has_summary && e.summary_status != 0)
      *table << "    episode FAILED live: " << FromLog(e.summary_message) << "\n";
    if (e.realtime.paced()) *table << "    " << transport::DescribeRealtime(e.realtime) << "\n";
    if (!evaluated && e.has_config && e.Complete()) *table << "    not evaluated: " << FromLog(why) << "\n";
    if (redrive) RedriveEpisode(e, &j, table, failed);
    episodes_json->push_back(j);
  }

  // ---- --redrive

  // Re-drives the episode in process or against the live controller; a
  // mismatch is named in *failed. Events of an episode whose configuration
  // is not in the log (an orphan, or a stranger's forgery) cannot be
  // re-driven: the episode is named and skipped, not a failure.
  void RedriveEpisode(const replay::Episode& e, nlohmann::json* j, std::ostream* table,
                      std::vector<std::string>* failed) {
    if (!e.has_config) {
      const std::string why = "no configuration in the log (" + FromLog(e.CompletenessNote()) + ")";
      (*j)["redrive"] = {{"ok", nullptr}, {"skipped", true}, {"message", "skipped: " + why}};
      *table << "    redrive: SKIPPED, episode " << e.episode_id << " has " << why << "\n";
      return;
    }
    ++redriven_;
    const replay::RedriveResult r = backend == "lcm" ? RedriveLive(e) : replay::Redrive(e);
    (*j)["redrive"] = results::RedriveJson(r);
    *table << "    redrive: " << (r.ok ? "OK, " : "FAILED, ") << FromLog(r.message) << "\n";
    if (!r.ok) failed->push_back("episode " + std::to_string(e.episode_id) + ": " + FromLog(r.message));
  }
  long redriven_ = 0;  // episodes --redrive re-drove (not the skipped)

  // ---- CSV

  void OpenCsv(std::unique_ptr<io::AtomicFile>* file) const {
    const Status s = io::AtomicFile::Open(csv, file);
    if (!s.ok()) Require(Status(s.code(), "--csv " + s.message()));
    (*file)->Write("episode,k,t,r,y,u,n,e\n");
  }

  // Steps 0..total_steps of an episode with a configuration (an episode
  // without one has no per-step data).
  static void WriteCsv(const replay::Episode& e, io::AtomicFile* out) {
    const double r = e.has_config ? e.spec.reference : 1.0;
    const double dt = e.has_config ? e.spec.dt_s : std::nan("");
    std::ostringstream rows;
    rows << std::setprecision(17);
    for (std::size_t i = 0; i < e.y.size(); ++i) {
      const auto k = static_cast<long>(i);
      rows << e.episode_id << "," << k << "," << static_cast<double>(k) * dt << "," << r << "," << e.y[i]
           << "," << e.u[i] << "," << e.n[i] << "," << r - e.y[i] << "\n";
    }
    out->Write(rows.str());
  }
};

}  // namespace
std::function<int()> RegisterReplay(CLI::App* app) { return RegisterCommand<ReplayCommand>(app); }

}  // namespace pidlab::cli
