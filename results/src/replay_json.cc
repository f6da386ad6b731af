#include "pidlab/results/replay_json.h"

#include <pidlab/lcmt_episode_config_fields.h>

#include <cmath>

#include "pidlab/results/results_json.h"

namespace pidlab::results {

nlohmann::json RealtimeJson(const transport::RealtimeStats& s) {
  return {{"missed_deadlines", s.missed_deadlines},
          {"lateness_p50_s", JsonNumber(s.lateness_p50_s)},
          {"lateness_p99_s", JsonNumber(s.lateness_p99_s)},
          {"lateness_max_s", JsonNumber(s.lateness_max_s)},
          {"rate_hz", JsonNumber(s.rate_hz)}};
}

nlohmann::json StreamJson(const replay::StreamStats& s) {
  nlohmann::json missing = nlohmann::json::array();
  for (const auto& [a, b] : s.missing) missing.push_back({a, b});
  return {{"expected", s.expected},
          {"received", s.received},
          {"duplicates", s.duplicates},
          {"conflicts", s.conflicts},
          {"out_of_order", s.out_of_order},
          {"beyond_end", s.beyond_end},
          {"filled_from_chunks", s.filled_from_chunks},
          {"missing", missing}};
}

nlohmann::json LogJson(const replay::LogContents& log, const std::string& path) {
  nlohmann::json out;
  out["log"] = path;
  out["events"] = log.events;
  out["pidlab_messages"] = log.pidlab_messages;
  out["self_test_events"] = log.self_test;
  out["foreign_events"] = log.foreign;
  out["unknown_type_events"] = log.unknown_type;
  out["decode_failures"] = log.decode_failures;
  out["unauthenticated_events"] = log.unauthenticated;
  out["unverified_events"] = log.unverified;
  out["other_prefix_events"] = log.other_prefix;
  out["eventnum_gaps"] = log.eventnum_gaps;
  out["clean_end"] = log.clean_end;
  out["bytes_read"] = log.bytes_read;
  out["file_bytes"] = log.file_bytes;
  out["notes"] = log.notes;
  out["episodes"] = nlohmann::json::array();
  return out;
}

namespace {

// A number; "inf", "-inf" or "nan" as text, as a spec writes infinity.
nlohmann::json ConfigNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}

}  // namespace

nlohmann::json ConfigJson(const lcmt_episode_config& m) {
  nlohmann::json j;
#define PIDLAB_JSON_D(name) j[#name] = ConfigNumber(m.name);
#define PIDLAB_JSON_I(name) j[#name] = m.name;
#define PIDLAB_JSON_S(name) j[#name] = m.name;
#define PIDLAB_JSON_A(name, count)    \
  j[#count] = m.count;                \
  j[#name] = nlohmann::json::array(); \
  for (double v : m.name) j[#name].push_back(ConfigNumber(v));
#define PIDLAB_JSON_N(name) j[#name] = m.name;
  PIDLAB_LCMT_EPISODE_CONFIG_FIELDS(PIDLAB_JSON_D, PIDLAB_JSON_I, PIDLAB_JSON_S, PIDLAB_JSON_A, PIDLAB_JSON_N)
#undef PIDLAB_JSON_D
#undef PIDLAB_JSON_I
#undef PIDLAB_JSON_S
#undef PIDLAB_JSON_A
#undef PIDLAB_JSON_N
  return j;
}

nlohmann::json EpisodeJson(const replay::Episode& e) {
  nlohmann::json j;
  j["prefix"] = e.prefix;
  j["episode_id"] = e.episode_id;
  j["complete"] = e.Complete();
  j["completeness"] = e.Complete() ? "complete" : e.CompletenessNote();
  j["total_steps"] = e.total_steps;
  j["plant_outputs"] = StreamJson(e.outputs);
  j["commands"] = StreamJson(e.commands);
  j["disturbance_samples"] = StreamJson(e.disturbances);
  if (e.has_summary)
    j["summary"] = {{"status", e.summary_status == 0 ? "ok" : "failed"},
                    {"step", e.summary_step},
                    {"message", e.summary_message}};
  if (e.realtime.paced()) j["realtime"] = RealtimeJson(e.realtime);
  if (e.has_config) {
    j["plant"] = e.spec.plant.name;
    j["gains"] = ToJson(e.spec.gains);
    j["dt_s"] = e.spec.dt_s;
    j["disturbance"] = ToString(e.spec.disturbance.kind);
    j["config"] = ConfigJson(e.config);
  } else {
    j["config_error"] = e.config_error;
  }
  return j;
}

nlohmann::json RedriveJson(const replay::RedriveResult& r) {
  nlohmann::json j = {{"ok", r.ok},
                      {"steps_checked", r.steps_checked},
                      {"first_mismatch_step", r.first_mismatch},
                      {"message", r.message}};
  if (r.first_mismatch >= 0) {
    j["logged_u"] = r.logged_u;
    j["recomputed_u"] = r.recomputed_u;
  }
  return j;
}

nlohmann::json EvaluatedEpisodeJson(const replay::Episode& e, evaluation::Evaluation* evaluation,
                                    bool* evaluated) {
  nlohmann::json j = EpisodeJson(e);
  if (e.has_config && e.spec.relay) {
    // A relay experiment is no step response: its IAE would mean nothing.
    j["controller_mode"] = "relay";
    j["evaluation"] = nullptr;
    j["evaluation_error"] =
        "a relay autotune episode, no step response (pidlab autotune --log analyses it; docs/autotune.md)";
    if (evaluation) *evaluation = evaluation::Evaluation{};
    if (evaluated) *evaluated = false;
    return j;
  }
  evaluation::Evaluation ev;
  const Status st = replay::EvaluateEpisode(e, &ev);
  const bool ok = st.ok();
  if (ok) {
    j["evaluation"] = ToJson(ev);
  } else {
    j["evaluation"] = nullptr;
    j["evaluation_error"] = st.message();
  }
  if (evaluation) *evaluation = std::move(ev);
  if (evaluated) *evaluated = ok;
  return j;
}

}  // namespace pidlab::results
