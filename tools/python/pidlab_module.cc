// pidlab from Python (docs/python.md): pidlab.evaluate and pidlab.tune,
// returning the dicts of `pidlab evaluate --json` and `pidlab tune --json`
// (the same code builds them: pidlab::results, results/). The extension is
// pidlab._pidlab; the package pidlab (with the lcm-gen'd messages) imports
// evaluate and tune from it.
//
// The keywords are the spec's fields (pidlab/spec/loop_spec.h): a flag's
// name with '_' for '-' (--sample-time -> sample_time), read by one archive
// over the field list, so a new field is a new keyword with nothing written
// here. Bad input raises ValueError with the CLI's one-line message, naming
// the keyword; an unknown keyword raises TypeError.

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <set>
#include <string>
#include <vector>

#include "identify_binding.h"
#include "pidlab/evaluation/evaluation.h"
#include "pidlab/results/autotune_json.h"
#include "pidlab/results/results_json.h"
#include "pidlab/results/spec_run.h"
#include "pidlab/results/tune_run.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/problem.h"

namespace py = pybind11;

namespace pidlab::python {
namespace {

[[noreturn]] void Bad(const std::string& message) { throw py::value_error(message); }

/// The dict of a JSON object: through Python's json module, so the keys,
/// nulls and every double (dumped with 17 significant digits) are exactly
/// those of the command line's output.
py::object ToPython(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

std::string Repr(const py::handle& o) {
  std::string text = py::repr(o).cast<std::string>();
  return spec::Truncate(text, 60);
}

/// A keyword's value as a field's type; ValueError naming the keyword.
template <typename T>
T Cast(const py::handle& o, const spec::Field& f, const char* expected) {
  try {
    return o.cast<T>();
  } catch (const py::cast_error&) {
    Bad(std::string(f.key) + " must be " + expected + ", not " + Repr(o));
  }
}

// A number; "inf"/"-inf" where the field takes infinity, "10%" for a spread.
double Number(const py::handle& o, const spec::Field& f) {
  if (py::isinstance<py::str>(o)) {
    std::string text = o.cast<std::string>();
    const bool percent = f.Has(spec::kPercent) && !text.empty() && text.back() == '%';
    if (percent) text.pop_back();
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (!text.empty() && *end == '\0' && (f.Has(spec::kInfinite) || percent)) return percent ? v / 100.0 : v;
    Bad(std::string(f.key) + " must be a number, not " + Repr(o));
  }
  return Cast<double>(o, f, "a number");
}

/// Reads the keywords given (not None) into a spec, records them in *given.
class KwargsReader {
 public:
  KwargsReader(const py::dict& kwargs, std::set<std::string>* given) : kwargs_(kwargs), given_(given) {}
  template <typename T>
  void Visit(const spec::Field& f, T* v) {
    known_.insert(f.key);
    if (!kwargs_.contains(f.key)) return;
    const py::object o = kwargs_[f.key];
    if (o.is_none()) return;
    Read(o, f, v);
    given_->insert(f.key);
  }
  const std::set<std::string>& known() const { return known_; }

 private:
  static void Read(const py::handle& o, const spec::Field& f, double* v) { *v = Number(o, f); }
  static void Read(const py::handle& o, const spec::Field& f, std::uint64_t* v) {
    *v = Cast<std::uint64_t>(o, f, "a whole number from 0 to 18446744073709551615");
  }
  static void Read(const py::handle& o, const spec::Field& f, int* v) {
    *v = Cast<int>(o, f, "a whole number");
  }
  static void Read(const py::handle& o, const spec::Field& f, bool* v) {
    *v = Cast<bool>(o, f, "True or False");
  }
  static void Read(const py::handle& o, const spec::Field& f, std::string* v) {
    *v = Cast<std::string>(o, f, "a string");
  }
  static void Read(const py::handle& o, const spec::Field& f, std::vector<double>* v) {
    if (py::isinstance<py::str>(o))
      Bad(std::string(f.key) + " must be a sequence of numbers, not " + Repr(o));
    std::vector<double> out;
    for (const py::handle item : py::iter(o)) out.push_back(Number(item, f));
    *v = std::move(out);
  }
  static void Read(const py::handle& o, const spec::Field& f, std::pair<double, double>* v) {
    std::vector<double> lo_hi;
    Read(o, f, &lo_hi);
    if (lo_hi.size() != 2) Bad(std::string(f.key) + " must be (LO, HI), not " + Repr(o));
    *v = {lo_hi[0], lo_hi[1]};
  }
  static void Read(const py::handle& o, const spec::Field& f, std::map<std::string, double>* v) {
    if (!py::isinstance<py::dict>(o))
      Bad(std::string(f.key) + " must be a dict {NAME: VALUE}, not " + Repr(o));
    std::map<std::string, double> out;
    for (const auto& [name, value] : o.cast<py::dict>())
      out[Cast<std::string>(name, f, "a dict of names")] = Number(value, f);
    *v = std::move(out);
  }

  const py::dict& kwargs_;
  std::set<std::string>* given_;
  std::set<std::string> known_;
};

/// *spec from the keywords; TypeError for a keyword no field has.
template <typename Spec>
void ReadKwargs(const char* function, const py::dict& kwargs, Spec* spec, std::set<std::string>* given) {
  KwargsReader r(kwargs, given);
  spec->Serialize(&r);
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first);
    if (key != "version" && r.known().count(key) == 0)
      throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" + key + "'");
  }
}

/// The keywords with the positional plant (a name, or (num, den); None: not
/// given, e.g. with model=FILE) and gains.
py::dict WithPositional(const py::object& plant, const py::object* gains, py::kwargs kwargs) {
  py::dict kw(kwargs);
  if (plant.is_none()) {
  } else if (py::isinstance<py::str>(plant)) {
    kw["plant"] = plant;
  } else {
    const py::sequence tf = plant.cast<py::sequence>();
    if (py::len(tf) != 2) Bad("plant (num, den) must have two lists, not " + std::to_string(py::len(tf)));
    kw["num"] = tf[0];
    kw["den"] = tf[1];
  }
  if (gains && !gains->is_none()) kw["gains"] = *gains;
  // refine=True/False: the flag's ceres/none.
  if (kw.contains("refine") && py::isinstance<py::bool_>(kw["refine"]))
    kw["refine"] = kw["refine"].cast<bool>() ? "ceres" : "none";
  return kw;
}

void Require(bool ok, const std::string& error) {
  if (!ok) Bad(error);
}

py::object EvaluatePy(const py::object& plant, const py::object& gains, py::kwargs kwargs) {
  spec::EvaluateSpec s;
  std::set<std::string> given;
  ReadKwargs("evaluate", WithPositional(plant, &gains, kwargs), &s, &given);
  // The same code as `pidlab evaluate --spec` and `pidlab serve` (json/spec_run.h).
  nlohmann::json result;
  Status status;
  {
    py::gil_scoped_release release;
    status = results::EvaluateSpecJson(spec::ToJson(s), &result, nullptr, &given);
  }
  Require(status.ok(), status.message());
  return ToPython(result);
}

py::object TunePy(const py::object& plant, py::kwargs kwargs) {
  spec::TuningSpec s;
  tune::BuildOptions build;
  ReadKwargs("tune", WithPositional(plant, nullptr, kwargs), &s, &build.given);
  // The same code as `pidlab tune` and `pidlab serve` (tune/problem.h).
  tune::TuningProblem problem;
  Status status = tune::BuildTuning(s, build, &problem);
  Require(status.ok(), status.message());
  tune::TuningResult result;
  {
    py::gil_scoped_release release;
    status = tune::RunTuning(problem, tune::TuningRunOptions{}, &result);
  }
  Require(status.ok(), status.message());
  return ToPython(results::TuningJson(problem, result, "local"));
}

/// The field table of a spec: key, flag, help, unit, default, example, episode.
template <typename Spec>
py::object FieldTable() {
  nlohmann::json rows = nlohmann::json::array();
  for (const spec::FieldEntry& e : spec::Fields<Spec>())
    rows.push_back({{"key", e.field.key},
                    {"flag", spec::FlagName(e.field.key)},
                    {"help", e.field.help},
                    {"unit", e.field.unit},
                    {"default", e.default_value},
                    {"example", nlohmann::json::parse(e.field.example)},
                    {"episode", e.field.Has(spec::kEpisode)}});
  return ToPython(rows);
}

}  // namespace
}  // namespace pidlab::python

PYBIND11_MODULE(_pidlab, m) {
  using namespace pidlab::python;
  m.doc() =
      "pidlab: evaluate and tune PID gains (docs/python.md). Results are the dicts of "
      "`pidlab evaluate --json` and `pidlab tune --json`; the keywords are the spec's fields "
      "(spec_fields()).";
  m.attr("__version__") = PIDLAB_VERSION;
  m.def("evaluate", &EvaluatePy,
        "evaluate(plant, gains, **spec): evaluates gains (kp, ki, kd) on a plant given by name "
        "('double_integrator', 'oscillator', 'stepper_motor', 'stepper_nonlinear' and their aliases, or "
        "'model:FILE', the model `pidlab identify --out` wrote; or model=FILE and no plant) or as "
        "(num, den) in descending powers of s. The keywords are the flags of `pidlab evaluate` with '_' for "
        "'-' "
        "(spec_fields('evaluate')); evaluate(**result['spec']) runs a result again. Returns the dict of "
        "`pidlab evaluate --json`.",
        py::arg("plant") = py::none(), py::arg("gains") = py::none());
  m.def("tune", &TunePy,
        "tune(plant, **spec): tunes PID gains and returns the dict of `pidlab tune --json`. The keywords are "
        "the "
        "flags of `pidlab tune` with '_' for '-' (spec_fields('tune')); the defaults are the command's. "
        "robust=True applies `pidlab tune --robust`; a keyword of the preset given next to it overrides its "
        "part, as the flags do.",
        py::arg("plant") = py::none());
  m.def(
      "read_spec",
      [](const std::string& which, py::kwargs kwargs) {
        std::set<std::string> given;
        if (which == "evaluate") {
          pidlab::spec::EvaluateSpec s;
          ReadKwargs("read_spec", py::dict(kwargs), &s, &given);
          return ToPython(pidlab::spec::ToJson(s));
        }
        if (which == "autotune") {
          pidlab::spec::AutotuneSpec s;
          ReadKwargs("read_spec", py::dict(kwargs), &s, &given);
          return ToPython(pidlab::spec::ToJson(s));
        }
        if (which != "tune") Bad("read_spec: '" + which + "' must be evaluate, tune or autotune");
        pidlab::spec::TuningSpec s;
        ReadKwargs("read_spec", py::dict(kwargs), &s, &given);
        pidlab::tune::ResolveTuningSpec(&s, given);
        return ToPython(pidlab::spec::ToJson(s));
      },
      "read_spec(which, **spec): the spec evaluate, tune or autotune would read from these keywords "
      "(defaults filled "
      "in, "
      "tune's robust preset resolved), as the dict every result carries under 'spec'; nothing is run or "
      "validated.",
      py::arg("which"));
  m.def(
      "spec_fields",
      [](const std::string& which) {
        if (which == "evaluate") return FieldTable<pidlab::spec::EvaluateSpec>();
        if (which == "tune") return FieldTable<pidlab::spec::TuningSpec>();
        if (which == "autotune") return FieldTable<pidlab::spec::AutotuneSpec>();
        Bad("spec_fields: '" + which + "' must be evaluate, tune or autotune");
      },
      "The fields of evaluate's, tune's or autotune's spec: key (the keyword), flag, help, unit, default, "
      "example, and "
      "whether it travels to the trio (episode).",
      py::arg("which") = "evaluate");
  m.def(
      "autotune",
      [](const std::string& log, int64_t episode, double max_ms, py::kwargs kwargs) {
        pidlab::spec::AutotuneSpec a;
        std::set<std::string> given;
        ReadKwargs("autotune", py::dict(kwargs), &a, &given);
        using pidlab::spec::NameStyle;
        const auto check = [](const pidlab::Status& st) {
          if (st.code() == pidlab::StatusCode::kInvalidInput) Bad(st.message());
          if (!st.ok()) throw std::runtime_error(st.message());
        };
        check(pidlab::results::CheckAutotuneScalar(a, NameStyle::kKey));
        pidlab::results::AutotuneDesignOptions design;
        check(pidlab::results::BuildAutotuneDesign(a, max_ms, NameStyle::kKey, &design));
        const pidlab::results::FixedPointRelay fixed = [&a](const pidlab::PidGains& previous,
                                                            const pidlab::PidOptions& pid,
                                                            pidlab::RelayTuneOptions* r) {
          return pidlab::results::AutotuneFixedPoint(a, previous, pid, NameStyle::kKey, r);
        };
        nlohmann::json out;
        bool adopted = false;
        check(pidlab::results::AutotuneLogJson(log, episode, design, nullptr, &out, &adopted, fixed));
        return ToPython(out);
      },
      "autotune(log, episode=0, max_ms=2, **spec): the relay autotune of a logged run (pidlab launch --log "
      "... -- pidlab autotune --backend lcm) recomputed from the log alone, as `pidlab autotune --log LOG "
      "--json` (docs/autotune.md): the experiment, the estimates with their intervals, the model, the "
      "design, "
      "the verification step found in the log, adopted, verdict and gains. The keywords are the autotune "
      "spec's fields (spec_fields('autotune')); from a log, the design's (method, robustness, response_time, "
      "max_overshoot) and the fixed-point check's (scalar, input_range) count, the relay is the log's. "
      "ValueError for an unreadable log, no relay episode in it or a bad keyword value.",
      py::arg("log"), py::arg("episode") = 0,
      py::arg("max_ms") = pidlab::results::AutotuneDesignOptions{}.max_ms);
  DefineIdentify(m);
}
