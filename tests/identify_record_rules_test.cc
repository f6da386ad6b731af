// What identify refuses before a fit, and what it says while one runs
// (docs/identify.md, "What a record must be"): absurd but finite records
// named by column, sample and CSV row; a CSV from a spreadsheet read; the
// progress callback once a start.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "identify_records.h"
#include "pidlab/identify/csv_data.h"
#include "pidlab/identify/identify.h"

namespace pidlab::identify {
namespace {

IdentifyData FirstOrderStep(std::size_t n = 200) {
  IdentifyData d;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.1 * static_cast<double>(k);
    d.t.push_back(t);
    d.u.push_back(t >= 1.0 ? 1.0 : 0.0);
    d.y.push_back(t >= 1.0 ? 2.0 * (1.0 - std::exp(-(t - 1.0) / 3.0)) : 0.0);
  }
  return d;
}

std::string Refusal(const IdentifyData& d, const std::vector<long>* rows = nullptr) {
  Sampling s;
  Status status = CheckData(d, &s, rows);
  if (status.ok()) status = CheckResponse(d);
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  return status.message();
}

TEST(RecordRules, ASampleBeyondTheMagnitudeLimitIsNamedByColumnSampleAndRow) {
  IdentifyData d = FirstOrderStep();
  d.y[57] = 1e300;
  std::vector<long> rows;
  for (long k = 0; k < static_cast<long>(d.t.size()); ++k) rows.push_back(k + 2);
  EXPECT_EQ(
      Refusal(d, &rows),
      "column y, sample 57 (row 59): 1e+300 is beyond 1e12 in magnitude, the limit of every number pidlab "
      "takes (rescale the column's units)");
}

TEST(RecordRules, AnOutlierFarBeyondTheColumnsSpreadIsRefused) {
  IdentifyData d = FirstOrderStep();
  d.y[120] = 5e11;  // within the magnitude limit, 1e12 times beyond the spread
  EXPECT_NE(Refusal(d).find("column y, sample 120: 5e+11 lies more than 1e12 times"), std::string::npos);
}

TEST(RecordRules, TimeIntervalsThatUnderflowAreRefused) {
  IdentifyData d = FirstOrderStep();
  for (std::size_t k = 0; k < d.t.size(); ++k) d.t[k] = 1e-301 * static_cast<double>(k);
  EXPECT_NE(Refusal(d).find("column t, sample 1: the interval 1e-301 s is below 1e-12 s"), std::string::npos);
}

TEST(RecordRules, AColumnScaledBy1e13IsRefusedNotFittedToNothing) {
  IdentifyData d = FirstOrderStep();
  for (double& t : d.t) t *= 1e13;
  EXPECT_NE(Refusal(d).find("column t"), std::string::npos);
}

TEST(RecordRules, AConstantOutputIsRefusedForEveryModelAndForAuto) {
  IdentifyData d = FirstOrderStep();
  std::fill(d.y.begin(), d.y.end(), 0.25);
  IdentifyResult r;
  const Status one = Identify(d, ProcessModelKind::kP1D, IdentifyOptions{}, &r);
  EXPECT_EQ(one.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(one.message(), "constant output: y is 0.25 throughout, so no response can be identified");
  AutoResult a;
  const Status automatic = IdentifyAuto(d, IdentifyOptions{}, &a);
  EXPECT_EQ(automatic.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(automatic.message(), one.message());
}

TEST(RecordRules, ACsvSavedByASpreadsheetWithBomCrlfAndQuotesIsRead) {
  const std::string path = std::filesystem::temp_directory_path() / "pidlab_bom_crlf.csv";
  {
    std::ofstream f(path, std::ios::binary);
    f << "\xef\xbb\xbf\"t\",\"u\",\"note\",\"y\"\r\n";
    for (int k = 0; k < 30; ++k) f << 0.5 * k << "," << (k >= 3) << ",\"a, b\"\"\"," << 0.1 * k << "\r\n";
  }
  IdentifyData d;
  std::vector<long> rows;
  const Status s = ReadCsvData(path, &d, &rows);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(d.t.size(), 30u);
  EXPECT_DOUBLE_EQ(d.y[29], 2.9);
  EXPECT_EQ(rows.front(), 2);
  EXPECT_EQ(rows.back(), 31);
  std::filesystem::remove(path);
}

TEST(RecordRules, AHeaderThatCannotBeReadIsEchoedWithItsInvisibleBytesEscaped) {
  const std::string path = std::filesystem::temp_directory_path() / "pidlab_bad_header.csv";
  {
    std::ofstream f(path, std::ios::binary);
    f << "time\tu\ty\r\n1,2,3\r\n";
  }
  IdentifyData d;
  const Status s = ReadCsvData(path, &d);
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_NE(s.message().find("the header 'time\\x09u\\x09y\\x0d' names no column t"), std::string::npos)
      << s.message();
  std::filesystem::remove(path);
}

TEST(Progress, IsCalledOnceAStartWithTheBestCostSoFar) {
  const IdentifyData d = FirstOrderStep();
  IdentifyOptions options;
  options.starts = 5;
  std::vector<int> done;
  std::vector<double> best;
  int total = 0;
  options.progress = [&](ProcessModelKind kind, int n, int of, double cost) {
    EXPECT_EQ(kind, ProcessModelKind::kP1D);
    done.push_back(n);
    best.push_back(cost);
    total = of;
  };
  IdentifyResult r;
  ASSERT_TRUE(Identify(d, ProcessModelKind::kP1D, options, &r).ok());
  ASSERT_EQ(static_cast<int>(done.size()), r.starts);
  EXPECT_EQ(total, r.starts);
  for (std::size_t i = 0; i < done.size(); ++i) EXPECT_EQ(done[i], static_cast<int>(i) + 1);
  for (std::size_t i = 1; i < best.size(); ++i) EXPECT_LE(best[i], best[i - 1]);
}

}  // namespace
}  // namespace pidlab::identify
