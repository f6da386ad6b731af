// pidlab report: regenerates the paper's Tables II-VI and Figures 9-21 with
// pidlab's re-evaluations and own tunings (see report/include/pidlab/report/report.h, docs/report.md).

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/io/files.h"
#include "pidlab/report/report.h"
#include "pidlab/report/trio_episode.h"

namespace pidlab::cli {
namespace {

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
                    "the paper's tables (CSV); default: the copy of data/paper_tables.csv built into pidlab");
    app->add_option("--seed", seed, "seed of every stochastic tuner")
        ->check(WholeNumber())
        ->capture_default_str();
    app->add_flag("--quick", quick, "reduced tuning budgets (one start; smoke tests)");
    app->add_flag("--no-figures", no_figures, "write report.md only");
    app->add_flag("--no-trio", no_trio,
                  "skip the LCM trio episode (25 s of lockstep, under 20 s here; --quick skips it too); the "
                  "section then shows the in-process sampled loop only");
    return [this] { return Run(); };
  }

  int Run() {
    report::ReportOptions options;
    options.paper_tables = paper_tables;
    options.seed = seed;
    options.quick = quick;
    options.figures = !no_figures;
    options.trio_absent_note = no_trio ? "skipped (--no-trio)" : "skipped (--quick)";
    // Every file of the report (report.md, the figures, the trio's log) is
    // written into a stage inside --out and moved into place only when all
    // are complete: a failure leaves the folder as it was.
    PrepareOutputDir(out_dir, "--out");  // an unwritable folder is bad input (exit 2), before the work
    // So is a read-only old report.md (or trio.log), found now and not after the tunings.
    for (const char* file : {"report.md", "trio.log"})
      if (const Status st = io::CheckWritableTarget((std::filesystem::path(out_dir) / file).string());
          !st.ok())
        throw BadInput("--out " + st.message());
    std::unique_ptr<io::StagedFolder> stage;
    Require(io::StagedFolder::Create(out_dir, &stage));
    options.out_dir = stage->path();
    if (!no_trio && !quick) {
      const std::string log = (std::filesystem::path(options.out_dir) / "trio.log").string();
      options.trio_runner = [log](const Plant& plant, const PidGains& g, double dt_s, double horizon_s,
                                  report::Metrics* m, std::string* note) {
        report::TrioEpisodeOptions trio;
        trio.log_path = log;
        return report::RunTrioEpisode(trio, plant, g, dt_s, horizon_s, m, note);
      };
    }
    std::vector<report::PaperRow> paper;
    if (options.paper_tables.empty()) {
      if (const Status st = report::ParsePaperTables(report::BuiltinPaperTablesCsv(),
                                                     "data/paper_tables.csv (built in)", &paper);
          !st.ok())
        throw std::runtime_error(st.message());
    } else {
      if (const Status st = report::ReadPaperTables(options.paper_tables, &paper); !st.ok())
        throw BadInput("--paper-tables " + st.message());
    }
    report::ReportData data;
    if (const Status st = report::ComputeReport(options, paper, &data); !st.ok())
      throw std::runtime_error(stage->Unstaged(st.message()));
    if (const Status st = report::WriteReport(&data); !st.ok())
      throw std::runtime_error(stage->Unstaged(st.message()));
    Require(stage->Commit());
    std::cout << "wrote " << (std::filesystem::path(out_dir) / "report.md").string() << " and "
              << data.figures.size() << " figures (" << data.rows.size() << " published rows, "
              << data.tunings.size() << " tunings; computation " << data.compute_time_s
              << " s, of it the motor section " << data.motor.compute_time_s
              << " s beside the rest and the robust section " << data.robust.compute_time_s << " s; figures "
              << data.figure_time_s << " s)\n";
    return 0;
  }
};

}  // namespace
std::function<int()> RegisterReport(CLI::App* app) { return RegisterCommand<ReportCommand>(app); }

}  // namespace pidlab::cli
