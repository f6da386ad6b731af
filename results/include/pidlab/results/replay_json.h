#pragma once
// The JSON objects of `pidlab replay --json` and of a paced run's `realtime`
// (evaluate, replay), built in one place for every front end.

#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/replay/log_reader.h"
#include "pidlab/replay/replay.h"
#include "pidlab/transport/pacing.h"

namespace pidlab::results {

/// The `realtime` object of a paced episode: exactly missed_deadlines,
/// lateness_p50_s, lateness_p99_s, lateness_max_s, rate_hz.
nlohmann::json RealtimeJson(const transport::RealtimeStats& stats);
/// One stream of an episode (plant outputs, commands, disturbance samples):
/// expected, received, duplicates, conflicts, out_of_order, beyond_end,
/// filled_from_chunks, missing [[from, to], ...].
nlohmann::json StreamJson(const replay::StreamStats& s);
/// The log's counts and notes, with an empty "episodes" array; `path` as given.
nlohmann::json LogJson(const replay::LogContents& log, const std::string& path);
/// The logged configuration, every field of the message by its .lcm name
/// (the X-macro <pidlab/lcmt_episode_config_fields.h>; arrays with their
/// count): the "config" of an episode. Infinity and NaN as "inf", "-inf",
/// "nan".
nlohmann::json ConfigJson(const lcmt_episode_config& m);
/// One episode without its evaluation and redrive; "config" when it has one.
nlohmann::json EpisodeJson(const replay::Episode& e);
/// The `redrive` object of an episode.
nlohmann::json RedriveJson(const replay::RedriveResult& r);
/// One episode's object of `pidlab replay --json` without its redrive:
/// EpisodeJson with "evaluation" (the object of `pidlab evaluate --json`,
/// recomputed by replay::EvaluateEpisode) or null and "evaluation_error".
/// *evaluation (if given) receives the evaluation, *evaluated whether it ran.
nlohmann::json EvaluatedEpisodeJson(const replay::Episode& e, evaluation::Evaluation* evaluation = nullptr,
                                    bool* evaluated = nullptr);

}  // namespace pidlab::results
