// The figure of `pidlab identify --plot` (figures.h).

#include <iomanip>
#include <sstream>

#include "pidlab/figures/figures.h"
#include "pidlab/plot/fit_figure.h"

namespace pidlab::figures {

bool IdentifyFigure(const identify::IdentifyData& data, const identify::IdentifyResult& result,
                    plot::Figure* figure, std::string* error) {
  std::ostringstream title;
  title << std::setprecision(6) << "identify: " << identify::ToString(result.model.kind) << ", fit "
        << result.fit_percent << " %, AIC " << result.aic
        << "\nresiduals: Ljung-Box p = " << result.whiteness.p_value
        << (result.whiteness.white ? " (white)" : " (NOT white)");
  figure->title = title.str();
  const plot::FitTrace trace{data.t,
                             data.y,
                             result.simulated,
                             result.residuals,
                             result.whiteness.autocorrelation,
                             result.whiteness.band};
  return plot::MakeFitFigure(trace, "y", figure, error);
}

}  // namespace pidlab::figures
