// pidlab report: regenerates the paper's Tables II-VI and Figures 9-21 with
// pidlab's re-evaluations and own tunings (see tools/report.h, docs/report.md).

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "report.h"

namespace pidlab::cli {
namespace {

// <repo>/../shared/reference/paper_tables.csv, the repo being the source tree
// this binary was built from (or the current directory's ancestors).
std::string DefaultPaperTables() {
#ifdef PIDLAB_SOURCE_DIR
  return (std::filesystem::path(PIDLAB_SOURCE_DIR) / ".." / "shared" / "reference" / "paper_tables.csv")
      .lexically_normal()
      .string();
#else
  return "../shared/reference/paper_tables.csv";
#endif
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs the paper's stepper-motor gains as one episode over the LCM trio, in a
// private network namespace, as a child process:
//   pidlab launch --isolated -- pidlab evaluate --backend lcm --loop sampled ... --json
// and reads the evaluation back from its JSON. The trio's stderr goes to
// <out>/trio.log.
bool RunTrio(const std::string& log_path, const Plant& plant, const PidGains& g, double dt_s,
             double horizon_s, report::Metrics* metrics, std::string* note) {
  std::error_code ec;
  const std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec || self.empty()) {
    *note = "cannot locate the pidlab executable (/proc/self/exe)";
    return false;
  }
  char gains[128];
  std::snprintf(gains, sizeof gains, "%.17g,%.17g,%.17g", g.kp, g.ki, g.kd);
  std::ostringstream dt, horizon;
  dt.precision(17);
  dt << dt_s;
  horizon.precision(17);
  horizon << horizon_s;
  const std::string evaluate = Quote(self) + " evaluate --plant " + Quote(plant.name) + " --gains " + gains +
                               " --loop sampled --dt " + dt.str() + " --horizon " + horizon.str() +
                               " --backend lcm --json";
  const std::string command =
      Quote(self) + " launch --isolated -- " + evaluate + " 2>" + Quote(log_path) + " </dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    *note = "cannot start: " + command;
    return false;
  }
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = pclose(pipe);
  if (status != 0) {
    *note = "`pidlab launch --isolated -- pidlab evaluate --backend lcm` failed (status " +
            std::to_string(status) + "); see " + log_path;
    return false;
  }
  try {
    const std::size_t brace = out.find('{');
    if (brace == std::string::npos) throw std::runtime_error("no JSON object in its output");
    const nlohmann::json j = nlohmann::json::parse(out.substr(brace));
    auto number = [&](const char* key) { return j.at(key).is_null() ? NAN : j.at(key).get<double>(); };
    metrics->stable = j.at("stable").get<bool>();
    metrics->iae = number("iae_undisturbed");
    metrics->iae_disturbed = number("iae");
    metrics->rise_time_s = number("rise_time_s");
    metrics->overshoot_pct = number("overshoot_pct");
    metrics->settling_time_s = number("settling_time_s");
  } catch (const std::exception& e) {
    *note = std::string("cannot read the trio's JSON: ") + e.what();
    return false;
  }
  *note =
      "one episode over the LCM trio (pidlab-plant, pidlab-controller, pidlab-disturbance) in a private "
      "network namespace, `pidlab launch --isolated -- pidlab evaluate --backend lcm --loop sampled --dt " +
      dt.str() + " --horizon " + horizon.str() + " --json`";
  return true;
}

struct ReportCommand {
  std::string out_dir = "report";
  std::string paper_tables;
  std::uint64_t seed = 1;
  bool quick = false;
  bool no_figures = false;
  bool no_trio = false;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Regenerate the paper's Tables II-VI and Figures 9-21: the published gains re-evaluated with "
        "standard "
        "definitions, pidlab's own tunings (nelder-mead, paper-nm, ziegler-nichols, ga, pso-gsa, each with "
        "its "
        "Ceres cross-check), and the stepper motor on the sampled loop. Writes DIR/report.md and PNG "
        "figures.");
    app->add_option("--out", out_dir, "output folder (created if needed)")->capture_default_str();
    app->add_option("--paper-tables", paper_tables,
                    "the paper's tables (CSV); default " + DefaultPaperTables());
    app->add_option("--seed", seed, "seed of every stochastic tuner")->capture_default_str();
    app->add_flag("--quick", quick, "reduced tuning budgets (one start; smoke tests)");
    app->add_flag("--no-figures", no_figures, "write report.md only");
    app->add_flag("--no-trio", no_trio,
                  "skip the LCM trio episode (25 s of lockstep, under 20 s here; --quick skips it too); the section then shows the "
                  "in-process sampled loop only");
    return [this] { return Run(); };
  }

  int Run() {
    report::ReportOptions options;
    options.paper_tables = paper_tables.empty() ? DefaultPaperTables() : paper_tables;
    options.out_dir = out_dir;
    options.seed = seed;
    options.quick = quick;
    options.figures = !no_figures;
    std::filesystem::create_directories(out_dir);
    options.trio_absent_note = no_trio ? "skipped (--no-trio)" : "skipped (--quick)";
    if (!no_trio && !quick) {
      const std::string log = (std::filesystem::path(out_dir) / "trio.log").string();
      options.trio_runner = [log](const Plant& plant, const PidGains& g, double dt_s, double horizon_s,
                                  report::Metrics* m, std::string* note) {
        return RunTrio(log, plant, g, dt_s, horizon_s, m, note);
      };
    }
    std::vector<report::PaperRow> paper;
    std::string error;
    if (!std::filesystem::is_regular_file(options.paper_tables))
      throw BadInput("paper tables not found: " + options.paper_tables + " (use --paper-tables FILE)");
    if (!report::ReadPaperTables(options.paper_tables, &paper, &error)) throw BadInput(error);
    report::ReportData data;
    if (!report::ComputeReport(options, paper, &data, &error)) throw std::runtime_error(error);
    if (!report::WriteReport(&data, &error)) throw std::runtime_error(error);
    std::cout << "wrote " << (std::filesystem::path(out_dir) / "report.md").string() << " and "
              << data.figures.size() << " figures (" << data.rows.size() << " published rows, "
              << data.tunings.size() << " tunings; computation " << data.compute_time_s << " s, figures "
              << data.figure_time_s << " s)\n";
    return 0;
  }
};

ReportCommand command;
const CommandRegistrar registrar("report", "regenerate the paper's tables and figures (report.md + PNGs)",
                                 [](CLI::App* sub) { return command.Register(sub); });

}  // namespace
}  // namespace pidlab::cli
