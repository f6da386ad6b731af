// pidlab batch: the AMIGO test batch (docs/deadtime.md, "The AMIGO test
// batch"): AMIGO's PID against pidlab's optimum of the load IAE under
// Ms <= 1.4 on every plant of Astrom and Hagglund's families P1-P9.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/plot/plot.h"
#include "pidlab/results/batch_json.h"
#include "pidlab/tune/batch.h"

using pidlab::tune::BatchOptions;
using pidlab::tune::BatchPlant;
using pidlab::tune::BatchResult;

namespace pidlab::cli {
namespace {

std::string Fixed(double v, int precision = 4) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream os;
  os << std::setprecision(precision) << v;
  return os.str();
}

std::string Joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ";") + x;
  return s.empty() ? "-" : s;
}

std::string Table(const std::vector<BatchResult>& results) {
  std::ostringstream os;
  os << std::left << std::setw(4) << "fam" << std::setw(18) << "plant" << std::setw(7) << "tau"
     << std::setw(9) << "K" << std::setw(9) << "Ti" << std::setw(9) << "Td" << std::setw(7) << "Ms"
     << std::setw(10) << "IAE_L"
     << "| " << std::setw(9) << "kp" << std::setw(9) << "ki" << std::setw(9) << "kd" << std::setw(7) << "Ms"
     << std::setw(10) << "IAE_L" << std::setw(7) << "ratio"
     << "at_bounds\n";
  for (const BatchResult& r : results) {
    os << std::setw(4) << r.plant.family << std::setw(18) << r.plant.label << std::setw(8) << Fixed(r.tau, 3)
       << std::setw(9) << Fixed(r.amigo_k) << std::setw(9) << Fixed(r.amigo_ti_s) << std::setw(9)
       << Fixed(r.amigo_td_s) << std::setw(7) << Fixed(r.amigo_ms) << std::setw(10) << Fixed(r.amigo_load_iae)
       << "| " << std::setw(9) << Fixed(r.gains.kp) << std::setw(9) << Fixed(r.gains.ki) << std::setw(9)
       << Fixed(r.gains.kd) << std::setw(7) << Fixed(r.ms) << std::setw(10) << Fixed(r.load_iae)
       << std::setw(7) << Fixed(r.ratio, 3) << Joined(r.at_bounds)
       << (r.message.empty() ? "" : "  (" + r.message + ")") << "\n";
  }
  return os.str();
}

std::string Csv(const std::vector<BatchResult>& results) {
  std::ostringstream os;
  os << std::setprecision(17)
     << "family,parameter,value,label,tau,amigo_k,amigo_ti_s,amigo_td_s,amigo_ms,amigo_load_iae,amigo_"
        "feasible,"
        "kp,ki,kd,tf,ms,load_iae,feasible,source,ratio,at_bounds\n";
  const auto num = [](double v) { return std::isfinite(v) ? Fixed(v, 17) : std::string(); };
  for (const BatchResult& r : results)
    os << r.plant.family << "," << r.plant.parameter << "," << r.plant.value << ",\"" << r.plant.label
       << "\"," << r.tau << "," << r.amigo_k << "," << r.amigo_ti_s << "," << r.amigo_td_s << ","
       << num(r.amigo_ms) << "," << num(r.amigo_load_iae) << "," << r.amigo_feasible << "," << num(r.gains.kp)
       << "," << num(r.gains.ki) << "," << num(r.gains.kd) << "," << num(r.gains.tf) << "," << num(r.ms)
       << "," << num(r.load_iae) << "," << r.feasible << "," << r.source << "," << num(r.ratio) << ","
       << Joined(r.at_bounds) << "\n";
  return os.str();
}

// The figure: pidlab's load IAE over AMIGO's against tau, a series per family.
void DrawFigure(const std::vector<BatchResult>& results, const std::string& path) {
  plot::Figure fig;
  fig.title = "AMIGO test batch: load IAE of pidlab (Ms <= 1.4) over AMIGO's";
  fig.output_path = path;
  fig.height_px = 700;
  plot::Panel& p = fig.panels.emplace_back();
  p.x_label = "tau = L / (L + T) of the FOPDT model [-]";
  p.y_label = "load IAE pidlab / AMIGO [-]";
  for (int f = 1; f <= 9; ++f) {
    plot::Series s;
    s.name = "P" + std::to_string(f);
    s.style = plot::Style::kPoints;
    static const char* const kColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                          "#8c564b", "#e377c2", "#7f7f7f", "#17becf"};
    s.color = kColors[f - 1];
    for (const BatchResult& r : results)
      if (r.plant.family == s.name && std::isfinite(r.ratio)) {
        s.x.push_back(r.tau);
        s.y.push_back(r.ratio);
      }
    if (!s.x.empty()) p.series.push_back(std::move(s));
  }
  if (p.series.empty()) p.series.push_back({"no ratio", {0.0}, {NAN}, plot::Style::kPoints, ""});
  std::string error;
  Require(plot::DrawPng(fig));
}

void WriteFile(const std::string& path, const std::string& text) { WriteOutputFile(path, text); }

struct BatchCommand {
  std::string set = "amigo", families, loop = "sampled", out_dir;
  bool json = false;
  int jobs = 0;
  BatchOptions options;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "The AMIGO test batch (Astrom and Hagglund's families P1-P9, docs/deadtime.md): for every plant "
        "AMIGO's PID and pidlab's optimum of the load IAE under Ms <= 1.4, both with the derivative filter "
        "Td/10, scored on the same loop; a summary table, or JSON, CSV and a figure.");
    app->add_option("--set", set, "the batch: amigo")->capture_default_str();
    app->add_option("--families", families, "only these families, e.g. P1,P4 (default: all)");
    app->add_option("--loop", loop,
                    "the loop both are scored on: sampled (continuous: delay-free plants only)")
        ->capture_default_str();
    app->add_option("--jobs", jobs, "threads over the plants (0 = every core)")->capture_default_str();
    app->add_flag("--json", json, "print one JSON object");
    app->add_option("--out", out_dir, "write batch.json, batch.csv and batch.png in this folder");
    return [this] { return Run(); };
  }

  std::vector<BatchPlant> Plants() const {
    std::vector<BatchPlant> all;
    if (!tune::TestBatchPlants(set, &all)) throw BadInput("--set " + Quote(set) + " must be amigo");
    if (families.empty()) return all;
    std::vector<std::string> names;
    std::stringstream ss(families);
    for (std::string f; std::getline(ss, f, ',');) names.push_back(f);
    std::vector<BatchPlant> selected;
    const Status status = tune::SelectFamilies(all, names, &selected);
    if (!status.ok()) throw BadInput("--families " + Quote(families) + ": " + status.message());
    return selected;
  }

  int Run() {
    const std::vector<BatchPlant> plants = Plants();
    if (loop == "sampled")
      options.loop = evaluation::LoopKind::kSampled;
    else if (loop == "continuous")
      options.loop = evaluation::LoopKind::kContinuous;
    else
      throw BadInput("--loop " + Quote(loop) + " must be sampled or continuous");
    if (jobs < 0 || jobs > 1024) throw BadInput("--jobs " + std::to_string(jobs) + " must be in [0, 1024]");
    options.jobs = jobs;
    if (!out_dir.empty()) PrepareOutputDir(out_dir, "--out");
    const bool tty = isatty(STDERR_FILENO) != 0;
    const auto start = std::chrono::steady_clock::now();
    std::vector<BatchResult> results;
    Require(tune::RunBatch(plants, options, &results, [tty](int done, int total) {
      if (!tty) return;
      std::fprintf(stderr, "\r  plant %4d / %d   ", done, total);
      std::fflush(stderr);
    }));
    if (tty) std::fprintf(stderr, "\r%40s\r", "");
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int used = jobs > 0 ? jobs : static_cast<int>(std::thread::hardware_concurrency());
    nlohmann::json j = {{"set", set},
                        {"loop", loop},
                        {"jobs", used},
                        {"wall_time_s", wall},
                        {"max_ms", options.max_ms},
                        {"filter_ratio", options.filter_ratio},
                        {"summary", results::BatchTallyJson(tune::TallyBatch(results))},
                        {"plants", nlohmann::json::array()}};
    for (const BatchResult& r : results) j["plants"].push_back(results::BatchResultJson(r));
    if (!out_dir.empty()) {
      WriteFile(out_dir + "/batch.json", j.dump(1) + "\n");
      WriteFile(out_dir + "/batch.csv", Csv(results));
      DrawFigure(results, out_dir + "/batch.png");
    }
    if (json) {
      std::cout << j.dump() << "\n";
    } else {
      const tune::BatchTally t = tune::TallyBatch(results);
      std::cout << Table(results) << "\n"
                << t.plants << " plants, " << loop << " loop, " << used << " jobs, " << Fixed(wall, 3)
                << " s; AMIGO feasible (Ms <= " << options.max_ms << ") on " << t.amigo_feasible
                << ", pidlab on " << t.pidlab_feasible << "; where AMIGO is feasible pidlab wins " << t.wins
                << ", ties " << t.ties << ", loses " << t.losses << " (ratio " << Fixed(t.best_ratio, 3)
                << " to " << Fixed(t.worst_ratio, 3) << "); largest Ms of pidlab " << Fixed(t.max_ms, 5)
                << "\n";
    }
    return 0;
  }
};

}  // namespace

std::function<int()> RegisterBatch(CLI::App* app) { return RegisterCommand<BatchCommand>(app); }

}  // namespace pidlab::cli
