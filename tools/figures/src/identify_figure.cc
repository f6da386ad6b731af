// The figure of `pidlab identify --plot` (figures.h).

#include <iomanip>
#include <sstream>

#include "pidlab/figures/figures.h"

namespace pidlab::figures {

bool IdentifyFigure(const identify::IdentifyData& data, const identify::IdentifyResult& result,
                    plot::Figure* figure, std::string* error) {
  if (result.simulated.size() != data.y.size() || result.residuals.size() != data.y.size()) {
    *error = "the fit has no simulated output to draw";
    return false;
  }
  std::ostringstream title;
  title << std::setprecision(6) << "identify: " << identify::ToString(result.model.kind) << ", fit "
        << result.fit_percent << " %, AIC " << result.aic
        << "\nresiduals: Ljung-Box p = " << result.whiteness.p_value
        << (result.whiteness.white ? " (white)" : " (NOT white)");
  figure->title = title.str();
  figure->height_px = 900;
  plot::Panel& outputs = figure->panels.emplace_back();
  outputs.title = "measured and simulated output";
  outputs.x_label = "t [s]";
  outputs.y_label = "y";
  outputs.series.push_back({"measured y", data.t, data.y, plot::Style::kLines, "#1f77b4"});
  outputs.series.push_back({"model", data.t, result.simulated, plot::Style::kLines, "#d62728"});
  plot::Panel& residuals = figure->panels.emplace_back();
  residuals.title = "residuals y - model";
  residuals.x_label = "t [s]";
  residuals.y_label = "e";
  residuals.series.push_back({"residual", data.t, result.residuals, plot::Style::kLines, "#2ca02c"});
  plot::Panel& acf = figure->panels.emplace_back();
  acf.title = "autocorrelation of the residuals, with the 95 % band of white noise";
  acf.x_label = "lag [samples]";
  acf.y_label = "r_k";
  std::vector<double> lags, up, down;
  for (int k = 1; k <= result.whiteness.lags; ++k) {
    lags.push_back(k);
    up.push_back(result.whiteness.band);
    down.push_back(-result.whiteness.band);
  }
  if (lags.empty()) {
    *error = "the residuals have no autocorrelation to draw";
    return false;
  }
  acf.series.push_back({"r_k", lags, result.whiteness.autocorrelation, plot::Style::kPoints, "black"});
  acf.series.push_back({"+-1.96/sqrt(N)", lags, up, plot::Style::kDashed, "#7f7f7f"});
  acf.series.push_back({"", lags, down, plot::Style::kDashed, "#7f7f7f"});
  return true;
}

}  // namespace pidlab::figures
