// pidlab.identify(t, u, y, model=...): the fit of `pidlab identify`
// (pidlab::identify) on arrays, returning the dict of `pidlab identify
// --json` (the same code builds it: pidlab::results). docs/python.md.

#include "identify_binding.h"

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "pidlab/identify/identify.h"
#include "pidlab/results/identify_json.h"

namespace py = pybind11;

namespace pidlab::python {
namespace {

py::object ToDict(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A sequence of numbers (a list, a tuple, a numpy array) as doubles; a
// ValueError naming the argument otherwise.
std::vector<double> Column(const py::object& values, const char* name) {
  try {
    return values.cast<std::vector<double>>();
  } catch (const py::cast_error&) {
    throw py::value_error(std::string("identify: ") + name + " must be a sequence of numbers");
  }
}

double OperatingPoint(const py::object& value, const char* name) {
  if (value.is_none()) return std::numeric_limits<double>::quiet_NaN();
  const double v = value.cast<double>();
  if (!std::isfinite(v)) throw py::value_error(std::string("identify: ") + name + " must be finite");
  return v;
}

// poles and zeros: None (a process model; tf: poles required, zeros 0) or
// the tf's numbers, checked by Identify.
void TfShape(const std::string& model, const py::object& poles, const py::object& zeros,
             identify::IdentifyOptions* options) {
  if (model != "tf") {
    if (!poles.is_none() || !zeros.is_none())
      throw py::value_error("identify: poles and zeros apply to model='tf' only, not '" + model + "'");
    return;
  }
  if (poles.is_none())
    throw py::value_error("identify: model='tf' needs poles=N (1.." + std::to_string(plant_sim::kMaxTfPoles) +
                          ")");
  const auto integer = [](const py::object& value, const char* name) {
    if (!py::isinstance<py::int_>(value))
      throw py::value_error(std::string("identify: ") + name + " must be an integer");
    return value.cast<int>();
  };
  options->poles = integer(poles, "poles");
  options->zeros = zeros.is_none() ? 0 : integer(zeros, "zeros");
}

py::object IdentifyPy(const py::object& t, const py::object& u, const py::object& y, const std::string& model,
                      int starts, std::uint64_t seed, const py::object& u0, const py::object& y0,
                      const py::object& poles, const py::object& zeros, const std::string& intersample,
                      const std::string& initial_condition, const std::string& loss,
                      const py::object& loss_scale, std::size_t max_samples) {
  identify::IdentifyData data{Column(t, "t"), Column(u, "u"), Column(y, "y")};
  identify::IdentifyOptions options;
  options.starts = starts;
  options.seed = seed;
  options.max_samples = max_samples;
  if (py::isinstance<py::str>(u0)) {
    if (u0.cast<std::string>() != "estimate")
      throw py::value_error("identify: u0 = '" + u0.cast<std::string>() +
                            "' must be a number, None or 'estimate'");
    options.estimate_u0 = true;
  } else {
    options.u0 = OperatingPoint(u0, "u0");
  }
  options.y0 = OperatingPoint(y0, "y0");
  TfShape(model, poles, zeros, &options);
  if (!identify::ParseIntersample(intersample, &options.intersample))
    throw py::value_error("identify: intersample = '" + intersample + "' must be 'zoh' or 'foh'");
  if (!identify::ParseInitialCondition(initial_condition, &options.initial_condition))
    throw py::value_error("identify: initial_condition = '" + initial_condition +
                          "' must be 'zero', 'steady-state' or 'estimate'");
  if (!identify::ParseLoss(loss, &options.loss))
    throw py::value_error("identify: loss = '" + loss + "' must be 'l2', 'huber' or 'cauchy'");
  if (!loss_scale.is_none()) options.loss_scale = loss_scale.cast<double>();
  if (std::string error; !options.IsValid(&error)) throw py::value_error("identify: " + error);
  identify::ProcessModelKind kind = identify::ProcessModelKind::kP1D;
  if (model != "auto" && !identify::Parse(model, &kind))
    throw py::value_error("identify: model = '" + model + "' must be one of " +
                          identify::ProcessModelKindNames() + "|auto");
  // As `pidlab identify` fits it: a record beyond max_samples decimated first.
  results::IdentifyRun run;
  Status status;
  {
    py::gil_scoped_release release;
    status = results::RunIdentify(data, model, options, &run);
  }
  const nlohmann::json& j = run.json;
  if (status.code() == StatusCode::kInvalidInput) throw py::value_error("identify: " + status.message());
  if (!status.ok()) throw std::runtime_error("identify: " + status.message());
  return ToDict(j);
}

}  // namespace

void DefineIdentify(py::module_& m) {
  m.def(
      "identify", &IdentifyPy,
      "identify(t, u, y, model='p1d', starts=16, seed=0, u0=None, y0=None, poles=None, zeros=None, "
      "intersample='zoh', initial_condition='zero', loss='l2', loss_scale=None, max_samples=10000): fits a "
      "process model (p1d, p2d, p2du, p1di, p2dz, or auto to choose among them by AIC) or a general "
      "transfer function (model='tf' with poles=N in 1..6 and zeros=M in 0..N-1, default 0) to the record "
      "t (s, uniform or not), u, y (lists or numpy arrays) and returns the dict of `pidlab identify "
      "--json`. u0, "
      "y0: the operating point (None: u0 the input the record rested at, u[0] or 0 by AIC, y0 estimated with "
      "the model; u0='estimate': "
      "fitted too). intersample: "
      "'zoh' (held) or 'foh' (linear between samples); initial_condition: 'zero', 'steady-state' or "
      "'estimate', as the CLI's --intersample and --initial-condition; loss: 'l2', 'huber' or 'cauchy' "
      "with loss_scale (None: derived from the l2 fit's residuals), as --loss and --loss-scale; a record "
      "longer than max_samples is decimated as --max-samples says (the dict's 'decimation'). Bad data or "
      "arguments raise ValueError naming the reason (docs/identify.md).",
      py::arg("t"), py::arg("u"), py::arg("y"), py::kw_only(), py::arg("model") = "p1d",
      py::arg("starts") = 16, py::arg("seed") = 0, py::arg("u0") = py::none(), py::arg("y0") = py::none(),
      py::arg("poles") = py::none(), py::arg("zeros") = py::none(), py::arg("intersample") = "zoh",
      py::arg("initial_condition") = "zero", py::arg("loss") = "l2", py::arg("loss_scale") = py::none(),
      py::arg("max_samples") = identify::kDefaultMaxSamples);
}

}  // namespace pidlab::python
