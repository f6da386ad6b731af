#include "pidlab/results/live_json.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "pidlab/results/replay_json.h"
#include "pidlab/results/results_json.h"

namespace pidlab::results {
namespace {

using monitor::EpisodeInfo;
using monitor::LiveView;
using monitor::MonitorSnapshot;

nlohmann::json PacingJson(const transport::PacingProgress& p) {
  return {{"step", p.steps},
          {"realtime_factor", JsonNumber(p.factor)},
          {"period_s", JsonNumber(p.period_s)},
          {"missed_deadlines", p.missed_deadlines},
          {"lateness_max_s", JsonNumber(p.lateness_max_s)},
          {"rate_hz", JsonNumber(p.rate_hz)},
          {"lateness_p50_upper_s", JsonNumber(p.UpperPercentile(0.50))},
          {"lateness_p99_upper_s", JsonNumber(p.UpperPercentile(0.99))},
          {"histogram", p.histogram}};
}

// A relay episode's relay as the watcher follows it (docs/autotune.md); null
// for any other episode.
nlohmann::json RelayJson(const monitor::RelayView& r) {
  if (!r.active) return nullptr;
  nlohmann::json j = {{"phase", r.phase},
                      {"why", r.why},
                      {"u0", JsonNumber(r.u0)},
                      {"y0", JsonNumber(r.y0)},
                      {"noise_sigma", JsonNumber(r.noise_sigma)},
                      {"hysteresis", JsonNumber(r.hysteresis)},
                      {"d_high", JsonNumber(r.d_high)},
                      {"d_low", JsonNumber(r.d_low)},
                      {"cycles", r.cycles},
                      {"restarts", r.restarts},
                      {"last_period_s", JsonNumber(r.last_period_s)},
                      {"last_amplitude", JsonNumber(r.last_amplitude)},
                      {"steps_followed", r.steps_followed},
                      {"estimates", nullptr}};
  if (r.estimates)
    j["estimates"] = {{"converged", r.converged},
                      {"period_s", JsonNumber(r.period_s)},
                      {"period_ci_s", JsonNumber(r.period_ci_s)},
                      {"ku", JsonNumber(r.ku)},
                      {"pu_s", JsonNumber(r.pu_s)},
                      {"ku_describing_function", JsonNumber(r.ku_describing_function)},
                      {"model",
                       {{"kind", r.integrating ? "ipdt" : "fopdt"},
                        {"gain", JsonNumber(r.gain)},
                        {"time_constant_s", JsonNumber(r.time_constant_s)},
                        {"delay_s", JsonNumber(r.delay_s)},
                        {"from", r.model_from}}}};
  return j;
}

nlohmann::json LiveEpisodeJson(const EpisodeInfo& e, int trio) {
  return {{"episode_id", e.episode_id},
          {"trio", trio},
          {"episode_id_text", std::to_string(e.episode_id)},  // exact where a JSON number is not (JavaScript)
          {"plant", e.plant},
          {"gains", {JsonNumber(e.kp), JsonNumber(e.ki), JsonNumber(e.kd)}},
          {"r", JsonNumber(e.r)},
          {"dt_s", JsonNumber(e.dt_s)},
          {"total_steps", e.total_steps},
          {"steps_done", e.steps_done},
          {"status", monitor::StatusName(e.status)},
          {"message", e.message},
          {"realtime", e.realtime.paced() ? RealtimeJson(e.realtime) : nlohmann::json(nullptr)},
          {"pacing", e.pacing ? PacingJson(*e.pacing) : nlohmann::json(nullptr)},
          {"relay", RelayJson(e.relay)}};
}

nlohmann::json HealthJson(const MonitorSnapshot& s) {
  nlohmann::json roles = nlohmann::json::object();
  for (int r = 0; r < monitor::kRoleCount; ++r) {
    const monitor::RoleHealth& h = s.roles[static_cast<std::size_t>(r)];
    roles[monitor::RoleName(static_cast<monitor::Role>(r))] = {
        {"last_heard_s", std::isnan(h.last_heard_s)
                             ? nlohmann::json(nullptr)
                             : nlohmann::json(std::max(0.0, s.now_s - h.last_heard_s))},
        {"pid", h.pid != 0 ? nlohmann::json(h.pid) : nlohmann::json(nullptr)}};
  }
  return {{"roles", roles},
          {"received", s.counters.received},
          {"undecodable", s.counters.undecodable},
          {"unauthenticated", s.counters.unauthenticated},
          {"replayed", s.counters.replayed},
          {"trajectory_requests", s.trajectory_requests}};
}

// The tunings the trios' monitors heard (a tuning publishes on its first
// trio), oldest first.
nlohmann::json TuningsJson(const LiveView& v) {
  std::vector<monitor::TuningInfo> all;
  for (const MonitorSnapshot& s : v.trios) all.insert(all.end(), s.tunings.begin(), s.tunings.end());
  std::stable_sort(all.begin(), all.end(),
                   [](const auto& a, const auto& b) { return a.first_heard_s < b.first_heard_s; });
  nlohmann::json out = nlohmann::json::array();
  for (const monitor::TuningInfo& t : all) {
    const bool any = std::isfinite(t.best_objective);
    out.push_back({{"tuning_id", t.tuning_id},
                   {"tuning_id_text", std::to_string(t.tuning_id)},
                   {"status", monitor::TuningStatusName(t.status)},
                   {"method", t.method},
                   {"objective", t.objective},
                   {"trios", t.trios},
                   {"iterations", t.iterations},
                   {"evaluations", t.evaluations},
                   {"best_objective", any ? nlohmann::json(t.best_objective) : nlohmann::json(nullptr)},
                   {"best_gains", any ? nlohmann::json(t.best_gains) : nlohmann::json(nullptr)}});
  }
  return out;
}

}  // namespace

nlohmann::json LiveStatusJson(const LiveView& v, const std::string& lcm_url,
                              const std::string& channel_prefix, const int64_t* selected_episode_id,
                              long dropped_frames) {
  nlohmann::json episodes = nlohmann::json::array();
  for (std::size_t i = 0; i < v.episodes.size(); ++i)
    episodes.push_back(LiveEpisodeJson(v.episodes[i], v.trio_of[i]));
  nlohmann::json status = {
      {"type", "live_status"},
      {"lcm_url", lcm_url},
      {"channel_prefix", channel_prefix},
      {"selected_episode_id",
       selected_episode_id ? nlohmann::json(*selected_episode_id) : nlohmann::json(nullptr)},
      {"selected_episode_id_text",
       selected_episode_id ? nlohmann::json(std::to_string(*selected_episode_id)) : nlohmann::json(nullptr)},
      {"episodes", episodes},
      {"tunings", TuningsJson(v)},
      {"health", v.trios.empty() ? nlohmann::json(nullptr) : HealthJson(v.trios.front())},
      {"dropped_frames", dropped_frames}};
  if (v.trios.size() > 1) {
    nlohmann::json trios = nlohmann::json::array();
    for (std::size_t t = 0; t < v.trios.size(); ++t)
      trios.push_back({{"trio", t + 1}, {"lcm_url", v.trio_urls[t]}, {"health", HealthJson(v.trios[t])}});
    status["trios"] = trios;
  }
  return status;
}

}  // namespace pidlab::results
