// pidlab_plot: the PNG gnuplot draws has the requested size, and the data
// files behind it hold exactly the series that were given.

#include "pidlab/plot/plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pidlab/plot/loop_figure.h"
#include "test_status.h"

namespace pidlab::plot {
namespace {

namespace fs = std::filesystem;

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pidlab_plot_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::vector<std::pair<double, double>> ReadData(const fs::path& path) {
  std::ifstream f(path);
  std::vector<std::pair<double, double>> rows;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    std::string x, y;
    is >> x >> y;
    rows.emplace_back(std::strtod(x.c_str(), nullptr), std::strtod(y.c_str(), nullptr));
  }
  return rows;
}

TEST_F(PlotTest, StackedLoopFigureIsAPngOfTheRequestedSizeBackedByTheExactData) {
  LoopTrace tr;
  tr.name = "kp=1";
  for (int k = 0; k < 300; ++k) {
    const double t = 0.01 * k;
    tr.t.push_back(t);
    tr.r.push_back(1.0);
    tr.y.push_back(1.0 - std::exp(-t) * std::cos(3.0 * t));
    tr.e.push_back(1.0 - tr.y.back());
    tr.u.push_back(k == 0 ? 500.0 : std::exp(-t) / 3.0);
    tr.n.push_back(k % 50 < 25 ? 0.1 : -0.1);
  }
  Figure dut;
  std::string error;
  ASSERT_TRUE(IsOk(MakeLoopFigure({tr}, UnitsOfPlant("stepper_motor"), "test figure", &dut)));
  ASSERT_EQ(dut.panels.size(), 4u);
  EXPECT_EQ(dut.panels[0].y_label, "y [rad]");
  EXPECT_EQ(dut.panels[2].x_label, "t [s]");
  dut.width_px = 640;
  dut.height_px = 900;
  dut.output_path = (dir_ / "loop.png").string();
  dut.data_dir = (dir_ / "data").string();
  ASSERT_TRUE(IsOk(DrawPng(dut)));
  int w = 0, h = 0;
  ASSERT_TRUE(ReadPngSize(dut.output_path, &w, &h));
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 900);
  // Panel 0 holds the reference (series 0) and y (series 1); panel 2 holds u.
  const auto y = ReadData(dir_ / "data" / "p0_s1.dat");
  ASSERT_EQ(y.size(), tr.t.size());
  for (std::size_t i = 0; i < y.size(); ++i) {
    EXPECT_EQ(y[i].first, tr.t[i]);
    EXPECT_EQ(y[i].second, tr.y[i]);
  }
  const auto u = ReadData(dir_ / "data" / "p2_s0.dat");
  ASSERT_EQ(u.size(), tr.u.size());
  for (std::size_t i = 0; i < u.size(); ++i) EXPECT_EQ(u[i].second, tr.u[i]);
  // The derivative kick is kept off the u axis and named in the title.
  EXPECT_LT(dut.panels[2].y_max, 500.0);
  EXPECT_NE(dut.panels[2].title.find("kick"), std::string::npos);
}

TEST_F(PlotTest, InvalidFiguresAreRefusedWithTheField) {
  Figure dut;
  dut.output_path = (dir_ / "x.png").string();
  std::string error;
  EXPECT_FALSE(OkInto(DrawPng(dut), &error));
  EXPECT_NE(error.find("no panels"), std::string::npos) << error;
  dut.panels.push_back(Panel{"", "t [s]", "y [-]", {Series{"y", {0.0, 1.0}, {1.0}, Style::kLines, ""}}});
  EXPECT_FALSE(OkInto(DrawPng(dut), &error));
  EXPECT_NE(error.find("2 x values but 1 y values"), std::string::npos) << error;
  dut.panels[0].series[0].y.push_back(2.0);
  dut.width_px = 10;
  EXPECT_FALSE(OkInto(DrawPng(dut), &error));
  EXPECT_NE(error.find("size"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dut.output_path));
}

TEST_F(PlotTest, AFailingGnuplotIsReportedAndLeavesNoPng) {
  Figure dut;
  dut.output_path = (dir_ / "x.png").string();
  dut.panels.push_back(Panel{"", "t [s]", "y [-]", {Series{"y", {0.0, 1.0}, {1.0, 2.0}, Style::kLines, ""}}});
  ::setenv("PIDLAB_GNUPLOT", "false", 1);
  std::string error;
  const bool ok = OkInto(DrawPng(dut), &error);
  ::unsetenv("PIDLAB_GNUPLOT");
  EXPECT_FALSE(ok);
  EXPECT_NE(error.find("failed with exit status 1"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dut.output_path));
}

TEST_F(PlotTest, NotAPngIsNotAPng) {
  {
    std::ofstream f(dir_ / "fake.png");
    f << "GIF89a not a png at all";
  }
  int w = 0, h = 0;
  EXPECT_FALSE(ReadPngSize((dir_ / "fake.png").string(), &w, &h));
}

}  // namespace
}  // namespace pidlab::plot
