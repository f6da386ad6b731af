// The figure of `pidlab identify --plot` (figures.h).

#include <iomanip>
#include <sstream>

#include "pidlab/figures/figures.h"
#include "pidlab/plot/fit_figure.h"

namespace pidlab::figures {

Status IdentifyFigure(const identify::IdentifyData& data, const identify::IdentifyResult& result,
                      plot::Figure* figure) {
  std::ostringstream title;
  title << std::setprecision(6) << "identify: " << identify::ToString(result.model.kind) << ", fit "
        << result.fit_percent << " %, AIC " << result.aic
        << (result.loss == identify::Loss::kL2 ? "" : ", " + identify::ToString(result.loss) + " loss")
        << "\nresiduals: Ljung-Box p = " << result.whiteness.p_value
        << (result.whiteness.white ? " (white)" : " (NOT white)");
  figure->title = title.str();
  const plot::FitTrace trace{data.t,
                             data.y,
                             result.simulated,
                             result.residuals,
                             result.whiteness.autocorrelation,
                             result.whiteness.band};
  if (Status st = plot::MakeFitFigure(trace, "y", figure); !st.ok()) return st;
  // The samples a robust loss down-weighted, marked on the measured output.
  if (!result.downweighted.empty()) {
    plot::Series marked;
    marked.name = "down-weighted by the " + identify::ToString(result.loss) + " loss (" +
                  std::to_string(result.downweighted.size()) + ")";
    marked.style = plot::Style::kPoints;
    marked.color = "red";
    for (int k : result.downweighted) {
      marked.x.push_back(data.t.at(static_cast<std::size_t>(k)));
      marked.y.push_back(data.y.at(static_cast<std::size_t>(k)));
    }
    figure->panels.front().series.push_back(marked);
  }
  return Status::Ok();
}

}  // namespace pidlab::figures
