// An autotune spec made a run (autotune_json.h, BuildAutotune).

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "pidlab/controller_export/export.h"
#include "pidlab/results/autotune_json.h"

namespace pidlab::results {
namespace {

using spec::DisplayName;
using spec::FormatNumber;
using spec::NameStyle;
using spec::Quote;

}  // namespace

Status CheckAutotuneScalar(const spec::AutotuneSpec& s, NameStyle style) {
  controller_export::Scalar v = controller_export::Scalar::kDouble;
  const std::string scalar = DisplayName("scalar", style), range = DisplayName("input_range", style);
  if (!controller_export::ParseScalar(s.scalar, &v) || v == controller_export::Scalar::kFloat)
    return Status::InvalidInput(scalar + " " + Quote(s.scalar) + " is not one of double, q31, q15");
  if (v == controller_export::Scalar::kDouble && !s.input_range.empty())
    return Status::InvalidInput(range + " is for " + scalar + " q31 or q15");
  if (v != controller_export::Scalar::kDouble && s.input_range.size() != 2)
    return Status::InvalidInput(scalar + " " + s.scalar + " needs " + range + " LO,HI (the export's)");
  return Status::Ok();
}

Status AutotuneFixedPoint(const spec::AutotuneSpec& s, const PidGains& previous, const PidOptions& pid,
                          NameStyle style, RelayTuneOptions* relay) {
  if (Status st = CheckAutotuneScalar(s, style); !st.ok()) return st;
  controller_export::Options o;
  controller_export::ParseScalar(s.scalar, &o.scalar);
  if (o.scalar == controller_export::Scalar::kDouble) return Status::Ok();
  o.input_min = s.input_range[0];
  o.input_max = s.input_range[1];
  controller_export::Controller c;
  c.gains = previous;
  c.pid = pid;
  controller_export::FixedScale scale;
  try {
    scale = controller_export::FixedPointScale(o, c);
  } catch (const std::invalid_argument& e) {
    return Status::InvalidInput(e.what());
  }
  relay->q_bits = scale.bits;
  relay->input_full_scale = scale.input_full_scale;
  relay->output_full_scale = scale.output_full_scale;
  return Status::Ok();
}

Status BuildAutotuneDesign(const spec::AutotuneSpec& s, double max_ms, NameStyle style,
                           AutotuneDesignOptions* design) {
  if (s.method != "amigo" && s.method != "simc" && s.method != "migo" && s.method != "optimal")
    return Status::InvalidInput(DisplayName("method", style) + " " + Quote(s.method) +
                                " is not amigo, simc, migo or optimal");
  AutotuneDesignOptions o;
  o.method = s.method;
  o.robustness = s.robustness;
  o.response_time_s = s.response_time_s;
  o.max_ms = max_ms;
  o.max_overshoot_pct = s.max_overshoot_pct;
  std::string why;
  if (!s.verify_gains.empty()) {
    const std::vector<double>& v = s.verify_gains;
    const std::string name = DisplayName("verify_gains", style);
    std::string list;
    for (double x : v) list += (list.empty() ? "" : ",") + FormatNumber(x);
    if (v.size() != 3 && v.size() != 4)
      return Status::InvalidInput(name + " " + list + " needs KP,KI,KD or KP,KI,KD,TF");
    o.verify_given = true;
    o.verify_gains = {v[0], v[1], v[2], v.size() == 4 ? v[3] : 0.0};
    if (!GainsAreValid(o.verify_gains, &why)) return Status::InvalidInput(name + " " + list + ": " + why);
  }
  if (!o.IsValid(&why)) return Status::InvalidInput(why);
  *design = o;
  return Status::Ok();
}

Status BuildAutotune(const spec::AutotuneSpec& s, const std::set<std::string>& given,
                     const PidGains& previous, const PidOptions& pid, double max_ms, NameStyle style,
                     AutotuneRun* run) {
  AutotuneRun out;
  RelayTuneOptions& relay = out.experiment.relay;
  relay.hold_s = s.hold_s;
  relay.u0 = s.u0;
  relay.y_limit = s.y_limit;
  relay.settled_cycles = s.settled_cycles;
  relay.tolerance = s.tolerance;
  relay.timeout_periods = s.timeout_periods;
  relay.max_restarts = s.max_restarts;
  if (!(s.relay_amplitude >= 0.0))
    return Status::InvalidInput(DisplayName("relay_amplitude", style) + " " +
                                FormatNumber(s.relay_amplitude) + " must be > 0");
  const double range = pid.output_max - pid.output_min;
  relay.amplitude = s.relay_amplitude > 0.0 ? s.relay_amplitude : std::isfinite(range) ? 0.2 * range : 1.0;
  if (s.relay_bias.empty()) {
    relay.bias = relay.amplitude / 3.0;
  } else {
    char* end = nullptr;
    relay.bias = std::strtod(s.relay_bias.c_str(), &end);
    if (end == s.relay_bias.c_str() || *end != '\0' || !(std::abs(relay.bias) <= spec::kMaxInputMagnitude))
      return Status::InvalidInput(DisplayName("relay_bias", style) + " " + Quote(s.relay_bias) +
                                  " is not a number of magnitude at most 1e12");
  }
  if (s.hysteresis >= 0.0) {
    relay.hysteresis = s.hysteresis;
    relay.noise_multiple = 0.0;
  } else {
    if (given.count("hysteresis"))
      return Status::InvalidInput(DisplayName("hysteresis", style) + " " + FormatNumber(s.hysteresis) +
                                  " must be >= 0");
    relay.hysteresis = 0.0;
    relay.noise_multiple = 3.0;
  }
  if (Status st = AutotuneFixedPoint(s, previous, pid, style, &relay); !st.ok()) return st;
  out.experiment.previous = previous;
  out.experiment.pid = pid;
  out.experiment.first_window_s = s.relay_time_s;
  out.experiment.max_window_s = s.max_time_s;
  std::string why;
  if (!out.experiment.IsValid(&why)) return Status::InvalidInput(why);
  if (Status st = BuildAutotuneDesign(s, max_ms, style, &out.design); !st.ok()) return st;
  *run = out;
  return Status::Ok();
}

}  // namespace pidlab::results
