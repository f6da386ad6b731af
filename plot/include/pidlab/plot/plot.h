#pragma once
// PNG figures drawn by gnuplot (Debian's gnuplot-nox), driven by the project.
//
// A Figure is one PNG file made of one or more Panels stacked vertically
// (for a control loop: y with r, e, u, n). Each panel has its own axis
// labels (give the unit in the label: "y(t) [rad]", "t [s]") and a legend
// of its Series. DrawPng writes every series to a whitespace-separated data
// file "p<panel>_s<series>.dat" (columns x y, 17 significant digits; NaN
// and infinite values are written as NaN, which gnuplot leaves out), writes
// the gnuplot script "figure.gp" next to them, runs gnuplot (its output goes
// to "gnuplot.log" there), checks its exit status and checks that the output
// is a PNG file.
//
// Terminal: pngcairo if gnuplot has it, plain png otherwise. The gnuplot
// executable is $PIDLAB_GNUPLOT if set, else "gnuplot" on the PATH.
//
// Example:
//   pidlab::plot::Figure fig;
//   fig.title = "Step response";
//   fig.output_path = "out/step.png";
//   pidlab::plot::Panel& p = fig.panels.emplace_back();
//   p.x_label = "t [s]";
//   p.y_label = "y [-]";
//   p.series.push_back({"reference r", t, r, pidlab::plot::Style::kDashed});
//   p.series.push_back({"output y", t, y});
//   if (const pidlab::Status s = pidlab::plot::DrawPng(fig); !s.ok()) { /* report s.message() */ }

#include <limits>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"

namespace pidlab::plot {

enum class Style {
  kLines,   // solid line through the points
  kDashed,  // dashed line (references, set points)
  kSteps,   // staircase held until the next x (zero-order-hold signals such as u)
  kPoints,  // markers only
};

struct Series {
  std::string name;          // legend entry; empty: no legend entry
  std::vector<double> x, y;  // same length, >= 1 point
  Style style = Style::kLines;
  std::string color;  // gnuplot colour ("black", "#1f77b4"); empty: automatic
};

struct Panel {
  std::string title;    // optional panel title
  std::string x_label;  // with unit, e.g. "t [s]"
  std::string y_label;  // with unit, e.g. "u [N m]"
  std::vector<Series> series;
  /// Fixed y range; NaN (the default) lets gnuplot autoscale that end.
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
};

struct Figure {
  std::string title;          // figure title (above the first panel); "\n" breaks a line
  std::vector<Panel> panels;  // stacked top to bottom, equal heights
  int width_px = 1000;        // PNG size in pixels, 100..10000
  int height_px = 800;
  std::string output_path;  // the PNG file to write (its folder must exist)
  /// Where the data files and figure.gp go. Empty: a temporary folder,
  /// removed afterwards. Otherwise the folder is created if needed and kept,
  /// so the figure can be checked against its data or redrawn by hand.
  std::string data_dir;

  /// Names the first field that is wrong and why.
  bool IsValid(std::string* error) const;
};

/// Draws `figure`. A failed Status (kIoFailed) with one line: invalid figure,
/// gnuplot missing or failing (its first error line is quoted) or no PNG
/// written. Never throws for a bad figure.
Status DrawPng(const Figure& figure);

/// Width and height of a PNG file from its IHDR chunk; false if `path` is
/// not a PNG file (signature and IHDR checked).
bool ReadPngSize(const std::string& path, int* width_px, int* height_px);

}  // namespace pidlab::plot
