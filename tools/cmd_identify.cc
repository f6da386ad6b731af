// pidlab identify: a process model (P1D, P2D, P2DU, P1DI, as MATLAB's idproc
// names them) fitted to the t, u, y columns of a CSV (docs/identify.md,
// "Identifying a model from a CSV").

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/identify/csv_data.h"
#include "pidlab/identify/identify.h"
#include "pidlab/json/identify_json.h"

namespace pidlab::cli {
namespace {

using identify::IdentifyResult;

std::string Num(double v, int precision = 8) {
  if (!std::isfinite(v)) return std::isnan(v) ? "-" : (v > 0 ? "inf" : "-inf");
  std::ostringstream os;
  os << std::setprecision(precision) << v;
  return os.str();
}

std::string Polynomial(const std::vector<double>& p) {
  std::string s = "[";
  for (std::size_t i = 0; i < p.size(); ++i) s += (i ? " " : "") + Num(p[i], 10);
  return s + "]";
}

const char* Formula(identify::ProcessModelKind kind) {
  switch (kind) {
    case identify::ProcessModelKind::kP1D:
      return "Kp e^(-Td s) / (1 + Tp1 s)";
    case identify::ProcessModelKind::kP2D:
      return "Kp e^(-Td s) / ((1 + Tp1 s)(1 + Tp2 s))";
    case identify::ProcessModelKind::kP2DU:
      return "Kp e^(-Td s) / (1 + 2 Zeta Tw s + (Tw s)^2)";
    case identify::ProcessModelKind::kP1DI:
      return "Kp e^(-Td s) / (s (1 + Tp1 s))";
  }
  return "";
}

std::string Table(const IdentifyResult& r) {
  std::ostringstream os;
  os << "model " << identify::ToString(r.model.kind) << ": " << Formula(r.model.kind) << "\n"
     << std::left << std::setw(10) << "parameter" << std::setw(18) << "value"
     << "standard error\n";
  for (std::size_t i = 0; i < r.names.size(); ++i)
    os << std::setw(10) << r.names[i] << std::setw(18) << Num(r.values[i], 10) << Num(r.standard_errors[i], 3)
       << "\n";
  if (!r.covariance_ok) os << "(no standard errors: " << r.covariance_message << ")\n";
  const TransferFunction tf = r.model.ToTransferFunction();
  os << "fit " << Num(r.fit_percent, 6) << " %, AIC " << Num(r.aic, 6) << " (N log(2 cost / N) + 2 p), cost "
     << Num(r.cost, 4) << "\n"
     << r.samples << " samples at dt " << Num(r.dt_s) << " s, offsets u0 " << Num(r.u0) << ", y0 "
     << Num(r.y0) << "\n"
     << r.starts_at_best << " of " << r.starts << " starts reached the best cost (within 1e-8 relative)\n"
     << "num " << Polynomial(tf.num) << " den " << Polynomial(tf.den) << " delay "
     << Num(r.model.delay_s(), 10) << " s\n";
  return os.str();
}

struct IdentifyCommand {
  std::string csv, model, out;
  bool json = false;
  identify::IdentifyOptions options;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Fit a process model to a record: the columns t (s, uniform), u and y of a CSV with a header (any "
        "order, other columns ignored). The record starts at rest: u0 = u[0], y0 = y[0]. Ceres fits the "
        "exact ZOH response with a continuous delay from several starts (docs/identify.md).");
    app->add_option("--csv", csv, "the CSV file with columns t, u, y")->required();
    app->add_option("--model", model, "the model: " + identify::ProcessModelKindNames())->required();
    app->add_option("--starts", options.starts, "starting points of the multi-start fit")
        ->capture_default_str();
    app->add_option("--seed", options.seed,
                    "digital shift of the starts' Sobol' design (0: the unshifted sequence)")
        ->capture_default_str();
    app->add_option("--u0", options.u0, "the input's operating point (default: the first sample of u)");
    app->add_option("--y0", options.y0, "the output's operating point (default: the first sample of y)");
    app->add_flag("--json", json, "print one JSON object");
    app->add_option("--out", out, "also write the JSON object to this file");
    return [this] { return Run(); };
  }

  int Run() {
    identify::ProcessModelKind kind = identify::ProcessModelKind::kP1D;
    if (!identify::Parse(model, &kind))
      throw BadInput("--model " + Quote(model) + " must be one of " + identify::ProcessModelKindNames());
    if (options.starts < 1 || options.starts > 1000)
      throw BadInput("--starts " + std::to_string(options.starts) + " must be in [1, 1000]");
    if (!std::isnan(options.u0) && !std::isfinite(options.u0))
      throw BadInput("--u0 " + Num(options.u0) + " must be finite");
    if (!std::isnan(options.y0) && !std::isfinite(options.y0))
      throw BadInput("--y0 " + Num(options.y0) + " must be finite");
    if (!out.empty()) CheckOutputFile(out, "--out");
    identify::IdentifyData data;
    Require(identify::ReadCsvData(csv, &data));
    IdentifyResult result;
    const Status status = identify::Identify(data, kind, options, &result);
    if (status.code() == StatusCode::kInvalidInput)
      throw BadInput("--csv " + Quote(csv) + ": " + status.message());
    Require(status);
    const nlohmann::json j = json::IdentifyResultJson(result);
    if (!out.empty()) {
      std::ofstream f(out);
      f << j.dump(1) << "\n";
      if (!f.flush()) throw BadInput("--out " + Quote(out) + " cannot be written");
    }
    std::cout << (json ? j.dump() + "\n" : Table(result));
    return 0;
  }
};

}  // namespace

std::function<int()> RegisterIdentify(CLI::App* app) {
  auto command = std::make_shared<IdentifyCommand>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

}  // namespace pidlab::cli
