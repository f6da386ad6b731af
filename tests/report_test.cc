// The paper report's data: the re-evaluation of the published gains must
// reproduce paper_tables.csv's ref_* columns, every table and tuning must be
// in the Markdown, and the report must be deterministic for a seed.

#include "pidlab/report/report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "test_status.h"

using pidlab::analysis::LoopFrequencyPoint;
using pidlab::tune::RefineVerdict;
using pidlab::tune::TuneMethod;

namespace pidlab::report {
namespace {

const char* const kPaperTables = PIDLAB_PAPER_TABLES;

ReportData QuickReport(std::uint64_t seed) {
  std::vector<PaperRow> paper;
  std::string error;
  EXPECT_TRUE(IsOk(ReadPaperTables(kPaperTables, &paper)));
  ReportOptions options;
  options.paper_tables = kPaperTables;
  options.quick = true;
  options.figures = false;
  options.seed = seed;
  ReportData data;
  EXPECT_TRUE(IsOk(ComputeReport(options, paper, &data)));
  return data;
}

// The quick report of seed 1, computed once for the tests that read it: the
// executable runs as one ctest test (tests/CMakeLists.txt), so that the
// report (about 6 s) is computed twice in all, not once per test.
const ReportData& SharedReport() {
  static const ReportData data = QuickReport(1);
  return data;
}

void ExpectRel(double expected, double actual, double rel, double abs, const std::string& what) {
  EXPECT_LE(std::abs(expected - actual), std::max(abs, rel * std::abs(expected)))
      << what << ": reference " << expected << ", report " << actual;
}

TEST(Report, ReEvaluationMatchesReferenceColumns) {
  const ReportData& data = SharedReport();
  ASSERT_EQ(data.rows.size(), 13u);
  for (const RowResult& r : data.rows) {
    const std::string what = r.paper.table + " " + r.paper.plant + " " + r.paper.method;
    ASSERT_TRUE(r.pidlab.stable) << what;
    ExpectRel(r.paper.ref_iae, r.pidlab.iae, 1e-6, 0.0, what + " IAE");
    ExpectRel(r.paper.ref_rise_time_s, r.pidlab.rise_time_s, 1e-4, 0.0, what + " rise");
    ExpectRel(r.paper.ref_overshoot_pct, r.pidlab.overshoot_pct, 1e-4, 1e-4, what + " overshoot");
    ExpectRel(r.paper.ref_settling_time_s, r.pidlab.settling_time_s, 1e-4, 0.0, what + " settling");
  }
}

TEST(Report, StepperSettlingDifferencesAreExplained) {
  const ReportData& data = SharedReport();
  int explained = 0;
  for (const RowResult& r : data.rows) {
    if (r.paper.plant != "stepper_motor" || r.paper.method != "nelder_mead") continue;
    bool found = false;
    for (const std::string& d : r.differences) found |= d.find("settling time") != std::string::npos;
    EXPECT_TRUE(found) << "Table " << r.paper.table << " +/-" << r.paper.disturbance_amplitude;
    ++explained;
  }
  EXPECT_EQ(explained, 6);
}

TEST(Report, MarkdownListsEveryTableTuningAndSection) {
  const ReportData& data = SharedReport();
  const std::string md = RenderMarkdown(data);
  for (const char* table :
       {"### Table II:", "### Table III:", "### Table IV:", "### Table V:", "### Table VI:"})
    EXPECT_NE(md.find(table), std::string::npos) << table;
  for (const char* plant : {"double_integrator", "oscillator", "stepper_motor"}) {
    for (TuneMethod m : {TuneMethod::kNelderMead, TuneMethod::kPaperNelderMead, TuneMethod::kZieglerNichols,
                         TuneMethod::kGeneticAlgorithm, TuneMethod::kPsoGsa}) {
      bool found = false;
      for (const Tuning& t : data.tunings)
        found |= t.plant == plant && t.method == m && t.disturbance_amplitude == 0.0;
      EXPECT_TRUE(found) << plant << " " << ToString(m);
    }
  }
  // Ziegler-Nichols is reported as not applicable on 1/s^2, applicable on the stepper.
  for (const Tuning& t : data.tunings) {
    if (t.method != TuneMethod::kZieglerNichols) continue;
    EXPECT_EQ(t.status, t.plant == "stepper_motor" ? TuningStatus::kTuned : TuningStatus::kNotApplicable)
        << t.plant << ": " << t.message;
    if (t.Tuned()) {
      EXPECT_EQ(t.summary.refine.verdict, RefineVerdict::kNotRun);
    } else {
      EXPECT_NE(t.message.find("no finite ultimate gain"), std::string::npos) << t.message;
    }
  }
  for (const Tuning& t : data.tunings) {
    if (t.Tuned() && t.method != TuneMethod::kZieglerNichols) {
      EXPECT_TRUE(t.summary.refine.ran) << ToString(t.method);
    }
  }
  EXPECT_NE(md.find("## Stepper motor on the sampled loop"), std::string::npos);
  EXPECT_NE(md.find("The LCM trio run was not available"), std::string::npos);  // no runner in this test
  EXPECT_NE(md.find("2 % band"), std::string::npos);
}

TEST(Report, TheMotorItselfRunsEveryMoveWithAndWithoutTheVoltageLimitNextToEquationThree) {
  const ReportData& data = SharedReport();
  const MotorSection& m = data.motor;
  ASSERT_EQ(m.moves.size(), 4u);
  EXPECT_EQ(m.moves[2], StepperMotorParameters{}.tooth_pitch_rad);
  EXPECT_EQ(m.voltage_limit_v, 24.0);
  ASSERT_EQ(m.sets.size(), 4u);  // paper's NM, pidlab's multi-start, its robust preset, tuned on the motor
  EXPECT_EQ(m.sets[0].gains.kp, 20.8836);
  // The robust preset: its filtered derivative is carried into the sampled loop.
  EXPECT_TRUE(m.robust_available);
  EXPECT_EQ(m.sets[2].name, "pidlab's robust preset");
  EXPECT_GT(m.sets[2].gains.tf, 0.0);
  EXPECT_NEAR(m.sets[2].gains.tf, m.sets[2].gains.kd / (10.0 * m.sets[2].gains.kp), 1e-12);
  EXPECT_EQ(m.sets[3].name, "Tuned on the motor itself");
  for (const MotorGainSet& set : m.sets) {
    EXPECT_TRUE(set.eq3_stable) << set.name;
    EXPECT_GT(set.eq3_iae_per_unit, 0.0) << set.name;
    ASSERT_EQ(set.rows.size(), 8u) << set.name;
    for (const MotorRow& r : set.rows) {
      const std::string what =
          set.name + " A = " + std::to_string(r.move_rad) + (r.limited ? " limited" : "");
      ASSERT_TRUE(r.stable) << what;
      EXPECT_TRUE(std::isfinite(r.iae_per_unit) && r.iae_per_unit > 0.0) << what;
      EXPECT_DOUBLE_EQ(r.iae_per_unit, r.iae / r.move_rad) << what;
      EXPECT_DOUBLE_EQ(r.ratio, r.iae_per_unit / set.eq3_iae_per_unit) << what;
      EXPECT_GT(r.peak_phase_voltage_v, 0.0) << what;
      EXPECT_GT(r.peak_phase_current_a, 0.0) << what;
      if (r.limited) {
        EXPECT_LE(r.peak_phase_voltage_v, 24.0) << what;
      }
    }
  }
  // The check: at 0.001 rad the paper's gains on the motor give
  // eq. (3)'s IAE/A within 1 % (without a limit); through 24 V they do not.
  const MotorRow& small = m.sets[0].rows[0];
  ASSERT_EQ(small.move_rad, 0.001);
  ASSERT_FALSE(small.limited);
  EXPECT_NEAR(small.ratio, 1.0, 0.01);
  EXPECT_GT(m.sets[0].rows[4].ratio, 2.0);  // 0.001 rad through 24 V
  // The paper's 1 rad step loses steps on the motor through the 24 V drive.
  EXPECT_TRUE(m.sets[0].rows[7].lost_steps);
  EXPECT_GT(m.motor_tune.evaluations, 0);
  EXPECT_FALSE(m.curves.empty());
  const std::string md = RenderMarkdown(data);
  for (const char* text :
       {"## The motor itself", "### Where the linear design fails", "**In short:**", "| 0.001 | none | ",
        "| 0.001 | 24 V | ", "(one tooth pitch) | 24 V | ", "| 1 | 24 V | ", "**LOST**", "--robust",
        "Tuned on the motor itself", "### pidlab's robust preset: kp, ki, kd = "})
    EXPECT_NE(md.find(text), std::string::npos) << text;
  EXPECT_EQ(md.find("is not in this build"), std::string::npos);
}

// "Robust tuning": the three gain sets of each plant, the preset meeting its
// bounds with a finite noise gain, the ideal derivative's unbounded one, and
// frequency responses consistent with S + T = 1 and the loop analysis's Ms.
TEST(Report, RobustTuningComparesThePaperTheOptimumAndThePresetOnEveryPlant) {
  std::vector<PaperRow> paper;
  std::string error;
  ASSERT_TRUE(IsOk(ReadPaperTables(kPaperTables, &paper)));
  std::vector<RobustInput> inputs;
  for (const PaperRow& r : paper)
    if (r.method == "nelder_mead" && (r.table == "II" || r.table == "III" || r.table == "IV"))
      inputs.push_back({r.plant, r.gains});
  ASSERT_EQ(inputs.size(), 3u);
  RobustSection s;
  ASSERT_TRUE(IsOk(ComputeRobustSection(inputs, true, 1, &s)));
  ASSERT_EQ(s.plants.size(), 3u);
  for (const RobustPlant& p : s.plants) {
    ASSERT_EQ(p.sets.size(), 3u) << p.plant;
    const RobustGainSet& paper_set = p.sets[0];
    const RobustGainSet& optimum = p.sets[1];
    const RobustGainSet& robust = p.sets[2];
    EXPECT_EQ(paper_set.name, "paper Nelder-Mead");
    EXPECT_EQ(robust.name, "pidlab --robust");
    // The optimum of the paper's objective beats the paper's gains on it.
    EXPECT_LT(optimum.setpoint_iae, paper_set.setpoint_iae) << p.plant;
    EXPECT_NEAR(optimum.setpoint_iae, p.paper_objective_optimum, 1e-9 * p.paper_objective_optimum) << p.plant;
    for (const RobustGainSet& set : p.sets) {
      const std::string what = p.plant + " " + set.name;
      ASSERT_TRUE(set.stable) << what;
      EXPECT_GT(set.load_iae, 0.0) << what;
      EXPECT_EQ(set.monte_carlo.samples, 50) << what;
      EXPECT_GE(set.monte_carlo.stable_fraction, 0.0) << what;
      EXPECT_LE(set.monte_carlo.stable_fraction, 1.0) << what;
      ASSERT_EQ(set.response.size(), s.frequencies_rad_s.size()) << what;
      double peak_s = 0.0;
      for (const LoopFrequencyPoint& f : set.response) {
        EXPECT_LT(std::abs(f.s + f.t - 1.0), 1e-9) << what << " w " << f.w_rad_s;
        peak_s = std::max(peak_s, std::abs(f.s));
      }
      // The grid cannot exceed the analysis's true peak (which is refined).
      EXPECT_LE(peak_s, set.analysis.ms * (1.0 + 1e-9)) << what;
      if (set.gains.tf == 0.0) {
        EXPECT_TRUE(std::isinf(set.analysis.noise_gain)) << what;  // the ideal derivative
      }
    }
    // The preset: filtered derivative, every bound met, finite noise gain,
    // and a smaller load IAE than the paper objective's optimum.
    EXPECT_GT(robust.gains.tf, 0.0) << p.plant;
    EXPECT_TRUE(std::isfinite(robust.analysis.noise_gain)) << p.plant;
    EXPECT_LE(robust.analysis.ms, s.max_ms * (1.0 + 1e-3)) << p.plant;
    EXPECT_LE(robust.analysis.slowest_time_constant_s, 2.5) << p.plant;
    EXPECT_LT(robust.load_iae, optimum.load_iae) << p.plant;
  }
  std::ostringstream md;
  RenderRobustSection(md, s);
  const std::string text = md.str();
  for (const char* want : {"## Robust tuning", "### 1/s^2", "### 1/(s^2+1)", "### stepper motor, eq. (3)",
                           "| paper Nelder-Mead | ", "| pidlab, paper objective | ", "| pidlab --robust | ",
                           "unbounded", "50 plants drawn", "seed 1", "the optimum of the paper's objective"})
    EXPECT_NE(text.find(want), std::string::npos) << want;
}

TEST(Report, TwoDegreesOfFreedomLowerTheOvershootAndLeaveLoadIaeAndMsAlone) {
  const ReportData& data = SharedReport();
  ASSERT_EQ(data.two_dof.rows.size(), 3u);
  for (const TwoDofRow& r : data.two_dof.rows) {
    const tune::TwoDofSummary& t = r.summary;
    ASSERT_TRUE(t.ran) << r.plant << ": " << t.message;
    EXPECT_GE(t.b, 0.0) << r.plant;
    EXPECT_LE(t.b, 1.0) << r.plant;
    EXPECT_GE(t.c, 0.0) << r.plant;
    EXPECT_LE(t.c, 1.0) << r.plant;
    EXPECT_EQ(t.before.b, 1.0) << r.plant;
    EXPECT_EQ(t.before.c, 1.0) << r.plant;
    // The weights act on the reference only.
    EXPECT_NEAR(t.after.load_iae, t.before.load_iae, 1e-12 * t.before.load_iae) << r.plant;
    EXPECT_NEAR(t.after.ms, t.before.ms, 1e-12 * t.before.ms) << r.plant;
    EXPECT_LE(t.after.setpoint_iae, t.before.setpoint_iae) << r.plant;
    EXPECT_LT(t.after.overshoot_pct, t.before.overshoot_pct) << r.plant;
  }
  const std::string md = RenderMarkdown(data);
  EXPECT_NE(md.find("## Two degrees of freedom"), std::string::npos);
  EXPECT_NE(md.find("| stepper_motor | "), std::string::npos);
}

TEST(Report, DeterministicForASeed) {
  EXPECT_EQ(RenderMarkdown(SharedReport()), RenderMarkdown(QuickReport(1)));
}

TEST(Report, MissingPaperTablesNamesThePath) {
  std::vector<PaperRow> rows;
  std::string error;
  EXPECT_FALSE(OkInto(ReadPaperTables("/nonexistent/paper_tables.csv", &rows), &error));
  EXPECT_NE(error.find("/nonexistent/paper_tables.csv"), std::string::npos) << error;
}

TEST(Report, BadNumberNamesLineAndColumn) {
  const std::string path = ::testing::TempDir() + "/bad_paper_tables.csv";
  {
    std::ofstream out(path);
    out << "table,plant,method,disturbance_amplitude,kp,ki,kd,paper_rise_time_s,paper_overshoot_pct,"
           "paper_settling_time_s,paper_iae,ref_rise_time_s,ref_overshoot_pct,ref_settling_time_s,ref_iae\n"
        << "II,double_integrator,nelder_mead,,29.6,zero,28.3,1,1,1,1,1,1,1,1\n";
  }
  std::vector<PaperRow> rows;
  std::string error;
  EXPECT_FALSE(OkInto(ReadPaperTables(path, &rows), &error));
  EXPECT_NE(error.find("line 2"), std::string::npos) << error;
  EXPECT_NE(error.find("ki"), std::string::npos) << error;
  std::remove(path.c_str());
}

TEST(Report, MissingColumnIsNamed) {
  const std::string path = ::testing::TempDir() + "/short_paper_tables.csv";
  {
    std::ofstream out(path);
    out << "table,plant,method,kp,ki,kd\nII,double_integrator,nelder_mead,1,2,3\n";
  }
  std::vector<PaperRow> rows;
  std::string error;
  EXPECT_FALSE(OkInto(ReadPaperTables(path, &rows), &error));
  EXPECT_NE(error.find("missing column"), std::string::npos) << error;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace pidlab::report
