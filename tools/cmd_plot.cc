// pidlab plot: PNG figures of closed-loop runs (y with r, e, u, n), from an
// evaluation of one or several gain sets, or from the episodes of an LCM log.

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "pidlab/figures/figures.h"
#include "pidlab/io/files.h"
#include "pidlab/plot/loop_figure.h"
#include "pidlab/tune/problem.h"
#include "pidlab/tune/time_scale.h"

using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::spec::NameStyle;

namespace pidlab::cli {
namespace {

// The plant and loop flags of evaluate; --gains is repeatable here.
struct PlotSpec {
  spec::PlantSpec plant;
  spec::LoopSpec loop;
  template <typename Archive>
  void Serialize(Archive* a) {
    plant.Serialize(a);
    loop.Serialize(a);
  }
};

struct PlotCommand {
  SpecFlags flags;
  std::vector<std::string> gains;
  std::string log_path;
  std::vector<long> episodes;
  std::string out_dir;
  std::string name;
  int width_px = 1200, height_px = 1000;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Draw PNG figures of the closed loop: step response y(t) with the reference, error e(t), control "
        "u(t) and disturbance n(t), with units and legends. Either from an evaluation (--plant, --gains, "
        "loop flags as for 'pidlab evaluate'; repeat --gains to overlay gain sets) or from an LCM log "
        "(--log FILE [--episode ID]). Writes DIR/NAME.png and the data behind it in DIR/NAME_data/.");
    flags.Register(app, PlotSpec{}, /*spec_file=*/false);
    app->add_option("--gains", gains, "KP,KI,KD; repeat to overlay several gain sets")->take_all();
    app->add_option("--log", log_path, "plot the episodes of this LCM log instead of an evaluation");
    app->add_option("--episode", episodes, "with --log: only these episode ids (repeatable; default all)")
        ->take_all();
    app->add_option("--out", out_dir, "output folder (created if needed)")->required();
    app->add_option("--name", name, "file name stem (default: evaluation, or the log file's stem)");
    app->add_option("--width", width_px, "PNG width in px")->capture_default_str();
    app->add_option("--height", height_px, "PNG height in px")->capture_default_str();
    return [this] { return Run(); };
  }

  int Run() {
    plot::Figure figure;
    figure.width_px = width_px;
    figure.height_px = height_px;
    PlotSpec ps;
    std::set<std::string> given;
    flags.Apply(&ps, &given);
    if (name.empty())
      name = log_path.empty() ? "evaluation" : std::filesystem::path(log_path).stem().string();
    if (name.empty() || name.find('/') != std::string::npos)
      throw BadInput("--name " + Quote(name) + " must be a plain file name stem");
    if (!log_path.empty())
      FigureOfLog(&figure);
    else
      FigureOfEvaluation(ps, given, &figure);
    return Draw(&figure);
  }

  // Bad input (the folder, an old PNG that cannot be replaced) before any work.
  void CheckOutput() const {
    PrepareOutputDir(out_dir, "--out");
    if (const Status st = io::CheckWritableTarget(out_dir + "/" + name + ".png"); !st.ok())
      throw BadInput("--out " + st.message());
  }

  void FigureOfLog(plot::Figure* figure) const {
    if (!gains.empty() || flags.Given("plant") || flags.Given("num"))
      throw BadInput("--log cannot be combined with --plant/--gains (the log carries its own)");
    CheckOutput();
    std::string report;
    if (const Status st = figures::LogFigure(log_path, episodes, figure, &report); !st.ok())
      throw BadInput(st.message());
    if (!report.empty()) std::cerr << report;
  }

  void FigureOfEvaluation(const PlotSpec& ps, const std::set<std::string>& given,
                          plot::Figure* figure) const {
    if (!episodes.empty()) throw BadInput("--episode needs --log");
    if (gains.empty()) throw BadInput("--gains is required (or --log FILE)");
    Plant p;
    LoopOptions options;
    std::vector<PidGains> sets;
    for (const auto& g : gains) sets.push_back(ParseGains(g));
    // Framed for the loop: with neither --horizon nor --sample-time, the
    // closed loops' time scale, on every plant (tune/time_scale.h).
    Require(tune::BuildFigureLoop(ps.plant, ps.loop, sets, given, NameStyle::kFlag, &p, &options));
    const long points = options.loop == LoopKind::kSampled ? options.TotalSteps() : options.NumSamples();
    if (static_cast<double>(points) * static_cast<double>(sets.size()) > kMaxRecordedPoints)
      throw BadInput(std::to_string(sets.size()) + " curve(s) of " + std::to_string(points) +
                     " points each are more than 1e7 points: use a coarser --dt or --sample-time, a shorter "
                     "--horizon or fewer --gains");
    CheckOutput();
    if (const Status st = figures::EvaluationFigure(p, sets, options, figure); !st.ok())
      throw BadInput(st.message());
  }

  // The PNG and its data drawn into a stage inside --out and moved in only
  // when all of them are complete: a full disk leaves the folder as it was.
  int Draw(plot::Figure* figure) const {
    std::unique_ptr<io::StagedFolder> stage;
    Require(io::StagedFolder::Create(out_dir, &stage));
    figure->output_path = stage->path() + "/" + name + ".png";
    figure->data_dir = stage->path() + "/" + name + "_data";
    if (std::string error; !figure->IsValid(&error)) throw BadInput(error);
    const auto unstaged = [&stage](const Status& st) {
      return Status(st.code(), stage->Unstaged(st.message()));
    };
    Require(unstaged(plot::DrawPng(*figure)));
    // The script kept beside the data draws to the figure's own path, not the stage's.
    const std::string script = figure->data_dir + "/figure.gp";
    std::string text;
    Require(unstaged(io::ReadFile(script, 1 << 20, &text)));
    Require(unstaged(io::WriteFile(script, stage->Unstaged(text))));
    Require(unstaged(stage->Commit()));
    std::cout << out_dir + "/" + name + ".png"
              << "\n";
    return 0;
  }
};

}  // namespace
std::function<int()> RegisterPlot(CLI::App* app) { return RegisterCommand<PlotCommand>(app); }

}  // namespace pidlab::cli
