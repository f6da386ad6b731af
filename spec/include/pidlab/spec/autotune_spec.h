#pragma once
// The one description of a relay autotune (docs/autotune.md): the relay
// experiment, its fixed-point check and the design on the identified model,
// with its fields listed once in Serialize(Archive*) as loop_spec.h's are.
// `pidlab autotune` registers its flags from this list (next to the loop's
// EvaluateSpec flags), pidlab.autotune and pidlab.read_spec("autotune") read
// their keywords from it, and pidlab.spec_fields("autotune") lists it. What
// the values mean, and their checks, is one library function
// (results::BuildAutotune, autotune_json.h). The relay's defaults are
// RelayTuneOptions' own.

#include <string>
#include <vector>

#include "pidlab/controller/relay.h"
#include "pidlab/spec/field.h"

namespace pidlab::spec {

struct AutotuneSpec {
  double relay_amplitude = 0.0;  // 0: 20 % of the output range, 1 if unlimited
  std::string relay_bias;        // "": relay_amplitude / 3
  double hysteresis = -1.0;      // not given (< 0): 3 sigma of the hold's noise
  double hold_s = RelayTuneOptions{}.hold_s;
  double u0 = RelayTuneOptions{}.u0;
  double y_limit = RelayTuneOptions{}.y_limit;
  int settled_cycles = RelayTuneOptions{}.settled_cycles;
  double tolerance = RelayTuneOptions{}.tolerance;
  double timeout_periods = RelayTuneOptions{}.timeout_periods;
  int max_restarts = RelayTuneOptions{}.max_restarts;
  std::string scalar = "double";
  std::vector<double> input_range;  // fixed point: LO,HI
  double relay_time_s = 60.0, max_time_s = 7200.0;
  std::string method = "optimal";
  double robustness = 1.4, response_time_s = 0.0, max_overshoot_pct = 60.0;
  std::vector<double> verify_gains;  // KP,KI,KD[,TF]: these, not the design's

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(
        {"relay_amplitude", "relay amplitude d (units of u) > 0; 0: 20 % of the output range, 1 if unlimited",
         "", kNone, "0.5"},
        &relay_amplitude);
    a->Visit({"relay_bias",
              "relay bias b, |b| < d: +d+b above, -(d-b) below the operating point's input; empty: d/3 (an "
              "asymmetric relay, whose mean output gives a FOPDT gain); 0 is the symmetric relay (its FOPDT "
              "from the "
              "delay to the extremes, on a clean process)",
              "", kNone, R"("0.1")"},
             &relay_bias);
    a->Visit({"hysteresis",
              "relay hysteresis eps (units of y) >= 0; not given: 3 sigma of the noise the hold measures", "",
              kNone, "0.05"},
             &hysteresis);
    a->Visit({"hold", "the hold before the relay (the operating point and the noise)", "s", kNone, "20"},
             &hold_s);
    a->Visit({"u0", "the open-loop hold's input (when the previous gains are 0,0,0)", "", kNone, "0.3"}, &u0);
    a->Visit(
        {"y_limit",
         "stop the relay when |y - y0| (from the operating point) exceeds this; not given: 10 x the relay's "
         "expected amplitude 4 d / (pi Ku) on the plant (docs/autotune.md); inf: none",
         "", kInfinite, "2"},
        &y_limit);
    a->Visit(
        {"settled_cycles", "converged when this many cycles' periods and amplitudes agree", "", kNone, "4"},
        &settled_cycles);
    a->Visit({"tolerance", "their relative agreement", "", kNone, "0.05"}, &tolerance);
    a->Visit({"timeout_periods", "stop the relay if it has not converged within this many of its own periods",
              "", kNone, "30"},
             &timeout_periods);
    a->Visit({"max_restarts", "restarts after a load change", "", kNone, "1"}, &max_restarts);
    a->Visit(
        {"scalar",
         "the controller's relay: double (pidlab-controller's, checked bit for bit), q31 or q15 (pidlab "
         "export --autotune --scalar's in pidlab-controller-c: every switch checked, the input within 3 or "
         "2 LSB; needs input_range and finite output_limits)",
         "", kNone, R"("q31")"},
        &scalar);
    a->Visit({"input_range", "fixed point: LO,HI, the --input-range the controller was exported with", "",
              kNone, "[-2, 2]"},
             &input_range);
    a->Visit({"relay_time", "the first relay episode's relay window", "s", kNone, "30"}, &relay_time_s);
    a->Visit({"max_time", "the longest relay window", "s", kNone, "600"}, &max_time_s);
    a->Visit({"method",
              "the design on the identified model: optimal (pidlab's design engine, the default), amigo, simc or migo", "",
              kNone, R"("simc")"},
             &method);
    a->Visit({"robustness", "optimal and migo: the Ms bound they design to", "", kNone, "1.6"}, &robustness);
    a->Visit({"response_time", "optimal and migo: the response time they design to (0: the fastest at the Ms bound)", "s", kNone, "5"},
             &response_time_s);
    a->Visit({"max_overshoot", "adopt only gains whose step on the trio overshoots at most this, %", "",
              kNone, "30"},
             &max_overshoot_pct);
    a->Visit({"verify_gains",
              "KP,KI,KD[,TF]: verify these gains on the process instead of the design's, under the same "
              "verdict (their Ms on the identified model, then the step); the design is still made and "
              "shown beside them",
              "", kNone, "[1.2, 0.8, 0.1]"},
             &verify_gains);
  }
};

}  // namespace pidlab::spec
