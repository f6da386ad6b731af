#include "pidlab/plot/fit_figure.h"

namespace pidlab::plot {

namespace {

// MakeFitFigure() with the refusal's message in *error.
bool MakeFitFigureOrExplain(const FitTrace& trace, const std::string& output_label, Figure* figure,
                            std::string* error) {
  const std::size_t n = trace.t.size();
  if (n == 0 || trace.measured.size() != n || trace.simulated.size() != n || trace.residuals.size() != n) {
    *error = "the fit has no simulated output to draw";
    return false;
  }
  if (trace.autocorrelation.empty()) {
    *error = "the residuals have no autocorrelation to draw";
    return false;
  }
  figure->height_px = 900;
  Panel& outputs = figure->panels.emplace_back();
  outputs.title = "measured and simulated output";
  outputs.x_label = "t [s]";
  outputs.y_label = output_label;
  outputs.series.push_back({"measured", trace.t, trace.measured, Style::kLines, "#1f77b4"});
  outputs.series.push_back({"model", trace.t, trace.simulated, Style::kLines, "#d62728"});
  Panel& residuals = figure->panels.emplace_back();
  residuals.title = "residuals: measured - model";
  residuals.x_label = "t [s]";
  residuals.y_label = "e";
  residuals.series.push_back({"residual", trace.t, trace.residuals, Style::kLines, "#2ca02c"});
  Panel& acf = figure->panels.emplace_back();
  acf.title = "autocorrelation of the residuals, with the 95 % band of white noise";
  acf.x_label = "lag [samples]";
  acf.y_label = "r_k";
  std::vector<double> lags, up, down;
  for (std::size_t k = 1; k <= trace.autocorrelation.size(); ++k) {
    lags.push_back(static_cast<double>(k));
    up.push_back(trace.band);
    down.push_back(-trace.band);
  }
  acf.series.push_back({"r_k", lags, trace.autocorrelation, Style::kPoints, "black"});
  acf.series.push_back({"+-1.96/sqrt(N)", lags, up, Style::kDashed, "#7f7f7f"});
  acf.series.push_back({"", lags, down, Style::kDashed, "#7f7f7f"});
  return true;
}

}  // namespace

Status MakeFitFigure(const FitTrace& trace, const std::string& output_label, Figure* figure) {
  std::string why;
  if (!MakeFitFigureOrExplain(trace, output_label, figure, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::plot
