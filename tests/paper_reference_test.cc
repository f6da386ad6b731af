// The 13 gain sets of the paper against data/paper_tables.csv,
// whose ref_* columns were computed independently (MATLAB stepinfo).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "pidlab/evaluation/evaluation.h"
#include "test_status.h"

using pidlab::evaluation::Evaluate;
using pidlab::evaluation::EvaluateOptions;
using pidlab::evaluation::Evaluation;
using pidlab::evaluation::LoopOptions;

#ifndef PIDLAB_PAPER_TABLES
#error "PIDLAB_PAPER_TABLES (path of paper_tables.csv) must be defined by the build"
#endif

namespace pidlab {
namespace {

struct Row {
  std::string table, plant, method;
  double amplitude = 0.0;
  PidGains gains;
  double ref_rise_time_s = 0, ref_overshoot_pct = 0, ref_settling_time_s = 0, ref_iae = 0;
  std::string Name() const {
    return table + " " + plant + " " + method + (amplitude != 0.0 ? " A=" + std::to_string(amplitude) : "");
  }
};

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

// Reads the CSV; any problem is a hard failure, never a skip.
std::vector<Row> ReadRows(std::string* error) {
  std::ifstream f(PIDLAB_PAPER_TABLES);
  if (!f) {
    *error = std::string("cannot open ") + PIDLAB_PAPER_TABLES;
    return {};
  }
  std::string line;
  std::getline(f, line);
  const std::vector<std::string> header = SplitCsv(line);
  std::map<std::string, std::size_t> col;
  for (std::size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  for (const char* name : {"table", "plant", "method", "disturbance_amplitude", "kp", "ki", "kd",
                           "ref_rise_time_s", "ref_overshoot_pct", "ref_settling_time_s", "ref_iae"})
    if (!col.count(name)) {
      *error = std::string("column ") + name + " missing from " + PIDLAB_PAPER_TABLES;
      return {};
    }
  std::vector<Row> rows;
  while (std::getline(f, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> c = SplitCsv(line);
    if (c.size() != header.size()) {
      *error = "malformed line: " + line;
      return {};
    }
    Row r;
    r.table = c[col["table"]];
    r.plant = c[col["plant"]];
    r.method = c[col["method"]];
    const std::string& amp = c[col["disturbance_amplitude"]];
    r.amplitude = amp.empty() ? 0.0 : std::stod(amp);
    r.gains = {std::stod(c[col["kp"]]), std::stod(c[col["ki"]]), std::stod(c[col["kd"]])};
    r.ref_rise_time_s = std::stod(c[col["ref_rise_time_s"]]);
    r.ref_overshoot_pct = std::stod(c[col["ref_overshoot_pct"]]);
    r.ref_settling_time_s = std::stod(c[col["ref_settling_time_s"]]);
    r.ref_iae = std::stod(c[col["ref_iae"]]);
    rows.push_back(r);
  }
  return rows;
}

struct Evaluated {
  Row row;
  Evaluation ev;
};

// Each row evaluated once: the paper's continuous loop, ts = 0.05 s, n = 25 s,
// with the row's square disturbance at the plant input.
const std::vector<Evaluated>& EvaluatedRows() {
  static const std::vector<Evaluated> rows = [] {
    std::vector<Evaluated> out;
    std::string error;
    for (const Row& r : ReadRows(&error)) {
      Plant plant;
      if (!OkInto(MakePlant(r.plant, StepperMotorParameters{}, &plant), &error)) break;
      LoopOptions o;
      if (r.amplitude != 0.0) {
        o.disturbance.kind = DisturbanceKind::kSquare;
        o.disturbance.amplitude = r.amplitude;
      }
      Evaluated e{r, {}};
      if (!OkInto(Evaluate(plant, r.gains, o, EvaluateOptions{}, &e.ev), &error)) break;
      out.push_back(e);
    }
    return out;
  }();
  return rows;
}

TEST(PaperReference, CsvHasThirteenGainSets) {
  std::string error;
  const std::vector<Row> rows = ReadRows(&error);
  ASSERT_TRUE(error.empty()) << error;
  ASSERT_EQ(rows.size(), 13u) << PIDLAB_PAPER_TABLES;
  ASSERT_EQ(EvaluatedRows().size(), 13u) << "some rows could not be evaluated";
}

TEST(PaperReference, EveryLoopIsStable) {
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  for (const Evaluated& e : EvaluatedRows()) {
    EXPECT_TRUE(e.ev.stability.stable) << e.row.Name();
    EXPECT_TRUE(e.ev.step.valid) << e.row.Name() << ": " << e.ev.step.note;
  }
}

TEST(PaperReference, UndisturbedIaeMatchesRefIaeToOnePartIn1e4) {
  // ref_iae is the IAE of y1, the response to the reference alone (eq. 17).
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  for (const Evaluated& e : EvaluatedRows()) {
    EXPECT_NEAR(e.ev.iae_undisturbed, e.row.ref_iae, 1e-4 * e.row.ref_iae) << e.row.Name();
    if (e.row.amplitude == 0.0) {
      EXPECT_EQ(e.ev.iae, e.ev.iae_undisturbed) << e.row.Name();
    }
  }
}

TEST(PaperReference, DisturbedIaeDiffersFromTheUndisturbedOne) {
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  int disturbed = 0;
  for (const Evaluated& e : EvaluatedRows()) {
    if (e.row.amplitude == 0.0) continue;
    ++disturbed;
    EXPECT_GT(std::abs(e.ev.iae - e.ev.iae_undisturbed), 1e-3) << e.row.Name();
  }
  EXPECT_EQ(disturbed, 6);
}

TEST(PaperReference, RiseTimeMatchesRefRiseTimeToOnePercent) {
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  for (const Evaluated& e : EvaluatedRows())
    EXPECT_NEAR(e.ev.step.rise_time_s, e.row.ref_rise_time_s, 0.01 * e.row.ref_rise_time_s) << e.row.Name();
}

TEST(PaperReference, OvershootMatchesRefOvershootToOnePercentOrFiveHundredthsOfAPoint) {
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  for (const Evaluated& e : EvaluatedRows()) {
    const double tol = std::max(0.01 * e.row.ref_overshoot_pct, 0.05);
    EXPECT_NEAR(e.ev.step.overshoot_pct, e.row.ref_overshoot_pct, tol) << e.row.Name();
  }
}

TEST(PaperReference, SettlingTimeMatchesRefSettlingTimeToOnePercent) {
  ASSERT_EQ(EvaluatedRows().size(), 13u);
  for (const Evaluated& e : EvaluatedRows())
    EXPECT_NEAR(e.ev.step.settling_time_s, e.row.ref_settling_time_s, 0.01 * e.row.ref_settling_time_s)
        << e.row.Name();
}

}  // namespace
}  // namespace pidlab
