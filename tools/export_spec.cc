#include "export_spec.h"

#include "cli_spec.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/tune/problem.h"

namespace pidlab::cli {

bool ExportController(const spec::EvaluateSpec& s, spec::NameStyle style, controller_export::Controller* c,
                      std::string* error) {
  if (s.gains.empty()) {
    *error = style == spec::NameStyle::kFlag ? "--gains is required (or --from FILE, --spec FILE)"
                                             : "gains are required";
    return false;
  }
  PidGains g;
  evaluation::LoopOptions loop;
  if (Status built = tune::BuildController(s, style, &g, &loop); !built.ok()) {
    *error = built.message();
    return false;
  }
  c->gains = evaluation::LoopGains(g, loop);
  c->pid = PidOptionsAt(loop.pid, loop.dt_s);
  // The spec's setpoint weights (c = 0 for derivative_on measurement), in the PID's options.
  c->setpoint_weight_b = c->pid.setpoint_weight_b;
  c->setpoint_weight_c = c->pid.setpoint_weight_c;
  return controller_export::ControllerIsValid(*c, error);
}

std::string DescribePlant(const spec::PlantSpec& p) {
  if (p.plant.empty()) return "not given (no --plant)";
  std::string s = p.plant;
  if (!p.num.empty() || !p.den.empty())
    s += ", num " + FlagText(p.num) + ", den " + FlagText(p.den) + " (descending powers of s)";
  if (p.delay_s > 0.0) s += ", dead time " + FlagText(p.delay_s) + " s";
  return s;
}

std::string SpecText(const nlohmann::json& j) {
  std::string s = "{\n";
  std::size_t i = 0;
  for (const auto& item : j.items())
    s += "  " + nlohmann::json(item.key()).dump() + ": " + item.value().dump() +
         (++i < j.size() ? ",\n" : "\n");
  return s + "}";
}

}  // namespace pidlab::cli
