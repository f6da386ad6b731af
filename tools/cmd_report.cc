// pidlab report: regenerates the paper's Tables II-VI and Figures 9-21 with
// pidlab's re-evaluations and own tunings (see tools/report.h, docs/report.md).

#include <filesystem>
#include <iostream>

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

struct ReportCommand {
  std::string out_dir = "report";
  std::string paper_tables;
  std::uint64_t seed = 1;
  bool quick = false;
  bool no_figures = false;

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
    return [this] { return Run(); };
  }

  int Run() {
    report::ReportOptions options;
    options.paper_tables = paper_tables.empty() ? DefaultPaperTables() : paper_tables;
    options.out_dir = out_dir;
    options.seed = seed;
    options.quick = quick;
    options.figures = !no_figures;
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
