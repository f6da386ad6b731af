// The paper report's shared helpers: see report_internal.h.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "format.h"
#include "report_internal.h"

using pidlab::evaluation::LoopOptions;
using pidlab::tune::TuneMethod;

namespace pidlab::report {

std::string Gains(const PidGains& g) { return Num(g.kp, 5) + ", " + Num(g.ki, 5) + ", " + Num(g.kd, 5); }

std::string PlantTitle(const std::string& plant) {
  if (plant == "double_integrator") return "1/s^2 (the paper's \"linear system\")";
  if (plant == "oscillator") return "1/(s^2+1) (the paper's \"nonlinear system\")";
  if (plant == "stepper_motor") return "stepper motor, eq. (3) with Table I";
  return plant;
}

std::string MethodTitle(const std::string& csv_method) {
  if (csv_method == "ziegler_nichols") return "Ziegler-Nichols";
  if (csv_method == "nelder_mead") return "Nelder-Mead";
  if (csv_method == "pso_gsa") return "PSO-GSA";
  if (csv_method == "genetic_algorithm") return "GA";
  return csv_method;
}

bool RelClose(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b));
}

Plant BuiltinPlant(const std::string& name) {
  Plant p;
  std::string error;
  if (const Status st = MakePlant(name, StepperMotorParameters{}, &p); !st.ok())
    throw std::invalid_argument(st.message());
  return p;
}

LoopOptions PaperLoop(double amplitude) {
  LoopOptions o;  // continuous, ts = 0.05 s, n = 25 s
  if (amplitude > 0.0) {
    o.disturbance.kind = DisturbanceKind::kSquare;
    o.disturbance.amplitude = amplitude;
    o.disturbance.period_s = kSquarePeriodS;
  }
  return o;
}

const PaperRow* FindRow(const std::vector<RowResult>& rows, const std::string& table,
                        const std::string& plant, const std::string& method, double amplitude) {
  for (const RowResult& r : rows) {
    if (r.paper.table == table && r.paper.plant == plant && r.paper.method == method &&
        (amplitude < 0.0 || std::abs(r.paper.disturbance_amplitude - amplitude) < 1e-9))
      return &r.paper;
  }
  return nullptr;
}

const Tuning* FindTuning(const std::vector<Tuning>& tunings, const std::string& plant, TuneMethod method,
                         double amplitude) {
  for (const Tuning& t : tunings) {
    if (t.plant == plant && t.method == method && std::abs(t.disturbance_amplitude - amplitude) < 1e-9)
      return &t;
  }
  return nullptr;
}

}  // namespace pidlab::report
