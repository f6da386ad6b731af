#include "pidlab/report/two_dof_section.h"

#include <chrono>

#include "format.h"
#include "pidlab/plant_sim/plants.h"

namespace pidlab::report {

namespace {

// ComputeTwoDofSection() with the refusal's message in *error.
bool ComputeTwoDofSectionOrExplain(const RobustSection& robust, TwoDofSection* section, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *section = TwoDofSection{};
  const StepperMotorParameters table_one;
  for (const RobustPlant& p : robust.plants) {
    for (const RobustGainSet& set : p.sets) {
      if (set.name.rfind("pidlab --robust", 0) != 0) continue;
      Plant plant;
      if (const Status st = MakePlant(p.plant, table_one, &plant); !st.ok()) {
        if (error) *error = st.message();
        return false;
      }
      TwoDofRow row;
      row.plant = p.plant;
      row.gains = set.gains;
      // The paper's continuous loop (unit step, ts = 0.05 s, n = 25 s), the set's own filter.
      const Status st = tune::TuneSetpointWeights(plant, set.gains, evaluation::LoopOptions{}, &row.summary);
      if (!st.ok()) {
        if (error) *error = st.message();
        return false;
      }
      section->rows.push_back(row);
    }
  }
  section->compute_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace

Status ComputeTwoDofSection(const RobustSection& robust, TwoDofSection* section) {
  std::string why;
  if (!ComputeTwoDofSectionOrExplain(robust, section, &why)) return Status::RunnerFailed(why);
  return Status::Ok();
}

void RenderTwoDofSection(std::ostream& os, const TwoDofSection& s) {
  os << "## Two degrees of freedom\n\n"
     << "The `pidlab tune --robust` gains above with setpoint weights b, c in [0, 1] tuned for the setpoint "
        "step (`pidlab tune --two-dof`'s second stage: an 11 x 11 grid, then Nelder-Mead; docs/two_dof.md), "
        "u = kp (b r - y) + ki/s (r - y) + kd s/(tf s + 1) (c r - y), on the paper's continuous loop. The "
        "weights act on the reference only: the load IAE (eq. 4 after a unit step at the plant input, r = 0) "
        "and Ms must not move, and do not.\n\n"
     << "| plant | b | c | setpoint IAE (b = c = 1 -> tuned) | overshoot % | load IAE | Ms |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const TwoDofRow& r : s.rows) {
    const tune::TwoDofSummary& t = r.summary;
    if (!t.ran) {
      os << "| " << r.plant << " | not run: " << t.message << " | | | | | |\n";
      continue;
    }
    os << "| " << r.plant << " | " << Num(t.b, 4) << " | " << Num(t.c, 4) << " | "
       << Num(t.before.setpoint_iae, 5) << " -> " << Num(t.after.setpoint_iae, 5) << " | "
       << Num(t.before.overshoot_pct, 4) << " -> " << Num(t.after.overshoot_pct, 4) << " | "
       << Num(t.before.load_iae, 6) << " -> " << Num(t.after.load_iae, 6) << " | " << Num(t.before.ms, 5)
       << " -> " << Num(t.after.ms, 5) << " |\n";
  }
  os << "\n";
}

}  // namespace pidlab::report
