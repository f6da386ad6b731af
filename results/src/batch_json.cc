#include "pidlab/results/batch_json.h"

#include "pidlab/results/results_json.h"

namespace pidlab::results {
namespace {

nlohmann::json GainsJson(const PidGains& g) {
  return {
      {"kp", JsonNumber(g.kp)}, {"ki", JsonNumber(g.ki)}, {"kd", JsonNumber(g.kd)}, {"tf", JsonNumber(g.tf)}};
}

}  // namespace

nlohmann::json BatchResultJson(const tune::BatchResult& r) {
  const tune::ProcessModel& m = r.model;
  return {{"family", r.plant.family},
          {"parameter", r.plant.parameter},
          {"value", r.plant.value},
          {"label", r.plant.label},
          {"plant_tf", r.plant.plant.tf.ToString()},
          {"delay_s", r.plant.plant.delay_s},
          {"model",
           {{"kind", tune::ToString(m.kind)},
            {"gain", m.gain},
            {"time_constants", m.time_constants},
            {"delay_s", m.delay_s}}},
          {"tau", r.tau},
          {"dt_s", r.dt_s},
          {"horizon_s", r.horizon_s},
          {"box", {{"lower", 0.0}, {"upper", r.box_upper}}},
          {"amigo",
           {{"k", r.amigo_k},
            {"ti_s", r.amigo_ti_s},
            {"td_s", r.amigo_td_s},
            {"gains", GainsJson(r.amigo_gains)},
            {"ms", JsonNumber(r.amigo_ms)},
            {"load_iae", JsonNumber(r.amigo_load_iae)},
            {"feasible", r.amigo_feasible}}},
          {"pidlab",
           {{"gains", GainsJson(r.gains)},
            {"ms", JsonNumber(r.ms)},
            {"load_iae", JsonNumber(r.load_iae)},
            {"feasible", r.feasible},
            {"source", r.source},
            {"at_bounds", r.at_bounds}}},
          {"ratio", JsonNumber(r.ratio)},
          {"wall_time_s", r.wall_time_s},
          {"message", r.message}};
}

nlohmann::json BatchTallyJson(const tune::BatchTally& t) {
  return {{"plants", t.plants},
          {"amigo_feasible", t.amigo_feasible},
          {"pidlab_feasible", t.pidlab_feasible},
          {"wins", t.wins},
          {"ties", t.ties},
          {"losses", t.losses},
          {"best_ratio", JsonNumber(t.best_ratio)},
          {"worst_ratio", JsonNumber(t.worst_ratio)},
          {"max_ms", JsonNumber(t.max_ms)}};
}

}  // namespace pidlab::results
