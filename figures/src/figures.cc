#include "pidlab/figures/figures.h"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "pidlab/evaluation/command_series.h"
#include "pidlab/plot/loop_figure.h"
#include "pidlab/replay/replay.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopKind;
using pidlab::evaluation::LoopOptions;
using pidlab::evaluation::SampledStep;

namespace pidlab::figures {

namespace {
std::string GainsLabel(const PidGains& g) {
  std::ostringstream os;
  os << std::setprecision(6) << "kp=" << g.kp << " ki=" << g.ki << " kd=" << g.kd;
  return os.str();
}

// Notes on the episodes of a log, one line per distinct note: a damaged log
// with 29 episodes of the same damage says so once, naming the episodes.
class EpisodeNotes {
 public:
  // `singular` and `plural` follow the episode(s): "not plotted: ...".
  void Add(long episode_id, const std::string& singular, const std::string& plural) {
    auto at =
        std::find_if(notes_.begin(), notes_.end(), [&](const Note& n) { return n.singular == singular; });
    if (at == notes_.end()) at = notes_.insert(notes_.end(), Note{singular, plural, {}});
    at->ids.push_back(episode_id);
  }
  std::string Lines() const {
    std::string out;
    for (const Note& n : notes_) {
      if (n.ids.size() == 1) {
        out += "note: episode " + std::to_string(n.ids[0]) + " " + n.singular + "\n";
        continue;
      }
      constexpr std::size_t kNamed = 5;
      std::string ids;
      for (std::size_t i = 0; i < std::min(n.ids.size(), kNamed); ++i)
        ids += (i ? ", " : "") + std::to_string(n.ids[i]);
      if (n.ids.size() > kNamed) ids += " and " + std::to_string(n.ids.size() - kNamed) + " more";
      out += "note: " + std::to_string(n.ids.size()) + " episodes (" + ids + ") " + n.plural + "\n";
    }
    return out;
  }

 private:
  struct Note {
    std::string singular, plural;
    std::vector<long> ids;
  };
  std::vector<Note> notes_;
};

}  // namespace

Status EvaluationFigure(const Plant& plant, const std::vector<PidGains>& gains, const LoopOptions& options,
                        plot::Figure* figure) {
  std::vector<plot::LoopTrace> traces;
  EvaluateOptions what;
  what.record_trajectory = true;
  what.compute_iae_continuous = false;
  for (const PidGains& g : gains) {
    Evaluation ev;
    if (Status st = Evaluate(plant, g, options, what, &ev); !st.ok()) return st;
    plot::LoopTrace tr;
    std::ostringstream name;
    name << GainsLabel(g) << std::setprecision(6) << " (IAE " << ev.iae
         << (ev.stability.stable ? "" : ", UNSTABLE") << ")";
    tr.name = name.str();
    if (!ev.stability.stable) {
      // Unstable: nothing was simulated; keep the legend entry honest with no curve.
      return Status::InvalidInput("gains " + GainsLabel(g) + " give an unstable loop: nothing to plot");
    }
    if (options.loop == LoopKind::kSampled) {
      for (const SampledStep& s : ev.trajectory) {
        tr.t.push_back(s.t);
        tr.r.push_back(s.r);
        tr.y.push_back(s.y);
        tr.e.push_back(s.r - s.y);
        tr.u.push_back(s.u);
        tr.n.push_back(s.n);
      }
    } else {
      tr.t = ev.t;
      tr.y = ev.y;
      tr.n = ev.n;
      tr.r.assign(ev.t.size(), options.reference);
      for (double y : ev.y) tr.e.push_back(options.reference - y);
      evaluation::CommandSeries series;
      evaluation::CommandAndLoadSeries(plant, g, options, ev, &series);
      if (series.u.size() == ev.t.size()) tr.u = std::move(series.u), tr.u_held = false;
    }
    traces.push_back(std::move(tr));
  }
  std::ostringstream title;
  title << std::setprecision(6) << plant.name << ", G(s) = " << plant.tf.ToString();
  if (plant.delay_s > 0.0) title << " e^(-" << plant.delay_s << " s)";
  title << "\n";
  if (options.loop == LoopKind::kSampled)
    title << "sampled loop, dt = " << options.dt_s << " s, every step";
  else
    title << "continuous loop (exact), y, e, n and u at the sample times ts = " << options.sample_time_s
          << " s"
          << (options.disturbance.kind != DisturbanceKind::kNone ? " (u of the undisturbed step)" : "");
  if (options.disturbance.kind != DisturbanceKind::kNone)
    title << ", " << ToString(options.disturbance.kind) << " disturbance " << options.disturbance.amplitude;
  return plot::MakeLoopFigure(traces, plot::UnitsOfPlant(plant.name), title.str(), figure);
}

Status LogFigure(const std::string& log_path, const std::vector<long>& episodes, plot::Figure* figure,
                 std::string* report) {
  replay::LogContents log;
  if (Status st = replay::ReadLog(log_path, replay::ReadOptions{}, &log); !st.ok()) return st;
  std::vector<std::string> said;  // the log's own notes, each once
  for (const auto& n : log.notes) {
    if (std::find(said.begin(), said.end(), n) != said.end()) continue;
    said.push_back(n);
    *report += "note: " + n + "\n";
  }
  EpisodeNotes notes;
  std::vector<plot::LoopTrace> traces;
  std::string plant_name;
  bool mixed_plants = false;
  for (long id : episodes) {
    bool found = false;
    for (const auto& e : log.episodes) found = found || e.episode_id == id;
    if (!found) {
      return Status::InvalidInput("--episode " + std::to_string(id) + " is not in " + log_path);
    }
  }
  for (const replay::Episode& e : log.episodes) {
    if (!episodes.empty() && std::find(episodes.begin(), episodes.end(), e.episode_id) == episodes.end())
      continue;
    if (!e.has_config) {
      notes.Add(e.episode_id, "not plotted: " + e.CompletenessNote(), "not plotted: " + e.CompletenessNote());
      continue;
    }
    if (!e.Complete())
      notes.Add(e.episode_id, "has gaps (drawn as breaks): " + e.CompletenessNote(),
                "have gaps (drawn as breaks): " + e.CompletenessNote());
    plot::LoopTrace tr;
    std::ostringstream name;
    name << "episode " << e.episode_id << ": " << GainsLabel(e.spec.gains);
    const DisturbanceOptions& d = e.spec.disturbance;
    if (d.kind == DisturbanceKind::kNone)
      name << ", no disturbance";
    else
      name << ", " << ToString(d.kind) << " " << d.amplitude;
    Evaluation ev;
    if (replay::EvaluateEpisode(e, &ev).ok()) name << std::setprecision(6) << " (IAE " << ev.iae << ")";
    tr.name = name.str();
    const double dt = e.spec.dt_s, r = e.spec.reference;
    for (long k = 0; k < e.total_steps; ++k) {
      const auto i = static_cast<std::size_t>(k);
      tr.t.push_back(static_cast<double>(k) * dt);
      tr.r.push_back(r);
      tr.y.push_back(e.y[i]);  // NaN where missing: gnuplot leaves a gap
      tr.e.push_back(r - e.y[i]);
      tr.u.push_back(e.u[i]);
      tr.n.push_back(e.n[i]);
    }
    if (!plant_name.empty() && plant_name != e.spec.plant.name) mixed_plants = true;
    plant_name = e.spec.plant.name;
    traces.push_back(std::move(tr));
  }
  *report += notes.Lines();
  if (traces.empty()) {
    return Status::InvalidInput("no episode with a configuration to plot in " + log_path);
  }
  std::ostringstream title;
  title << "log " << std::filesystem::path(log_path).filename().string() << ": "
        << (mixed_plants ? std::string("several plants") : plant_name)
        << ", sampled loop over LCM, every step";
  return plot::MakeLoopFigure(traces, plot::UnitsOfPlant(mixed_plants ? "" : plant_name), title.str(),
                              figure);
}

}  // namespace pidlab::figures
