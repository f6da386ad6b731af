// pidlab export: the discrete PID of a gain set and a loop as a
// dependency-free C99 module (controller/export/, docs/export.md).

#include <fstream>
#include <iostream>
#include <set>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "export_spec.h"
#include "pidlab/controller_export/export.h"
#include "pidlab/evaluation/closed_loop.h"
#include "pidlab/pil/firmware.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/problem.h"

using pidlab::controller_export::Controller;
using pidlab::controller_export::Generate;
using pidlab::controller_export::GeneratedCode;
using pidlab::controller_export::Options;
using pidlab::controller_export::ParseScalar;
using pidlab::controller_export::Scalar;
using pidlab::spec::NameStyle;

namespace pidlab::cli {
namespace {

/// A --json result's file: its echoed spec (an evaluation's or a tuning's)
/// and its gains.
nlohmann::json ReadResult(const std::string& path) {
  const std::string text = ReadInputFile(path, "--from", kMaxSpecFileBytes);
  nlohmann::json j;
  std::string error;
  if (const Status st = spec::ParseJsonText(text, &j); !st.ok())
    throw BadInput("--from " + Quote(path) + ": " + st.message());
  if (!j.is_object() || !j.contains("spec") || !j["spec"].is_object() || !j.contains("gains") ||
      !j["gains"].is_object())
    throw BadInput("--from " + Quote(path) +
                   " is not the --json output of pidlab tune or evaluate (no \"spec\" and \"gains\")");
  return j;
}

/// The spec and gains of a result file into *s (an evaluation's spec as it
/// is; a tuning's plant and loop).
void LoadResult(const std::string& path, spec::EvaluateSpec* s) {
  const nlohmann::json j = ReadResult(path);
  spec::EvaluateSpec evaluate;
  spec::TuningSpec tuning;
  if (const Status st = spec::FromJson(j["spec"], &evaluate, nullptr); st.ok()) {
    *s = evaluate;
  } else if (spec::FromJson(j["spec"], &tuning, nullptr).ok()) {
    s->plant = tuning.plant;
    s->loop = tuning.loop;
  } else {
    throw BadInput("--from " + Quote(path) + ": " + st.message());
  }
  // A tuning's setpoint weights (--two-dof, migo) go with its gains.
  if (j.contains("two_dof") && j["two_dof"].is_object() && j["two_dof"].value("ran", false)) {
    const auto& w = j["two_dof"]["setpoint_weights"];
    if (!w.is_array() || w.size() != 2 || !w[0].is_number() || !w[1].is_number())
      throw BadInput("--from " + Quote(path) + ": two_dof.setpoint_weights is not two numbers");
    s->loop.setpoint_weights = {w[0].get<double>(), w[1].get<double>()};
    const auto& f = j["two_dof"].value("setpoint_filter_s", nlohmann::json(0.0));
    if (!f.is_number())
      throw BadInput("--from " + Quote(path) + ": two_dof.setpoint_filter_s is not a number");
    s->loop.setpoint_filter_s = f.get<double>();
    s->loop.derivative_on = "error";  // c carries it
  }
  s->gains.clear();
  for (const char* key : {"kp", "ki", "kd"}) {
    const auto it = j["gains"].find(key);
    if (it == j["gains"].end() || !it->is_number())
      throw BadInput("--from " + Quote(path) + ": gains." + key + " is not a number");
    s->gains.push_back(it->get<double>());
  }
}

struct ExportCommand {
  SpecFlags flags;
  std::string from, lang, out, scalar = "double";
  bool autotune = false;
  std::vector<double> input_range;
  bool force = false;
  std::string pil_core;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Write the discrete PID of a gain set and a loop (--dt, --output-limits, --anti-windup, "
        "--integral, --derivative-filter, --derivative-on, --setpoint-weights, --setpoint-filter) as a "
        "dependency-free C99 "
        "module, pidlab_pid.h and "
        "pidlab_pid.c in --out: the controller DiscretePid runs, in its operation order (--scalar double: "
        "bit for bit), with manual mode, bumpless transfer and run-time gain and sample-time changes "
        "(docs/export.md).");
    flags.Register(app, spec::EvaluateSpec{});
    app->add_option("--from", from,
                    "take the spec and the gains from this --json output of pidlab tune or evaluate; flags "
                    "given as well override it");
    app->add_option("--lang", lang, "the language of the module: c")->required();
    app->add_option("--out", out, "write pidlab_pid.h and pidlab_pid.c into this folder")->required();
    app->add_option("--scalar", scalar,
                    "the controller's numbers: double (bit-identical to pidlab), float, q31 or q15 "
                    "(saturating fixed point, needs --input-range)")
        ->capture_default_str();
    app->add_option("--input-range", input_range,
                    "fixed point: LO,HI, the range of r and y the scalings are chosen for (outside it the "
                    "inputs saturate)")
        ->delimiter(',');
    app->add_flag(
        "--autotune", autotune,
        "also write pidlab_relay.h and pidlab_relay.c: the relay autotune's state machine over this PID "
        "(docs/autotune.md): double (bit for bit pidlab-controller's), q31 or q15 (pidlab autotune "
        "--scalar)");
    app->add_option("--pil", pil_core,
                    "also build the module into a firmware for an emulated Cortex-M (processor in the loop, "
                    "docs/pil.md): m3 (QEMU mps2-an385) or m4f (mps2-an386); writes OUT/pil.elf and "
                    "OUT/pil.json; needs scripts/install-deps.sh --pil");
    app->add_flag("--force", force,
                  "write the module even when the plant's sampled loop at --dt is unstable (it is refused "
                  "otherwise, exit 2)");
    return [this] { return Run(); };
  }

  Controller BuildController(const spec::EvaluateSpec& s) const {
    std::string error;
    Controller c;
    if (!ExportController(s, NameStyle::kFlag, &c, &error)) Require(flags.Named(Status::InvalidInput(error)));
    return c;
  }

  Options BuildOptions(const spec::EvaluateSpec& s) const {
    Options o;
    if (!ParseScalar(scalar, &o.scalar))
      throw BadInput("--scalar " + Quote(scalar) + " is not one of double, float, q31, q15");
    const bool fixed = o.scalar == Scalar::kQ31 || o.scalar == Scalar::kQ15;
    if (fixed && input_range.empty()) throw BadInput("--scalar " + scalar + " needs --input-range LO,HI");
    if (!input_range.empty()) {
      if (input_range.size() != 2)
        throw BadInput("--input-range " + FlagText(input_range) + " must be two numbers LO,HI");
      o.input_min = input_range[0];
      o.input_max = input_range[1];
    }
    std::string error;
    if (!o.IsValid(&error)) throw BadInput("--input-range: " + error);
    o.plant = DescribePlant(s.plant);
    o.spec_json = SpecText(spec::ToJson(s));
    o.pidlab_version = PIDLAB_VERSION;
    o.autotune = autotune;
    if (autotune && o.scalar == Scalar::kFloat)
      throw BadInput("--autotune with --scalar " + scalar +
                     ": the relay autotune is exported in double, q31 and q15");
    return o;
  }

  // The plant's sampled loop at dt, into the header; unstable: refused
  // unless --force, which writes it with a warning.
  void CheckLoop(const spec::EvaluateSpec& s, Options* options) const {
    tune::SampledControllerCheck check;
    Require(flags.Named(tune::CheckSampledController(s, NameStyle::kFlag, &check)));
    options->loop_check = check.verdict;
    if (check.stable) return;
    if (!force) throw BadInput(check.verdict);
    std::cerr << "pidlab export: warning: " << check.verdict << " (written: --force)\n";
    options->loop_check = "UNSTABLE, written with --force: " + check.verdict;
  }

  int Run() {
    if (lang != "c") throw BadInput("--lang " + Quote(lang) + " is not supported (c is)");
    pil::Core core = pil::Core::kM3;
    if (!pil_core.empty() && !pil::ParseCore(pil_core, &core))
      throw BadInput("--pil " + Quote(pil_core) + " is not m3 or m4f");
    if (!pil_core.empty() && autotune)
      throw BadInput("--pil with --autotune: the PIL firmware runs the PID only");
    if (!from.empty() && flags.Given("spec")) throw BadInput("--from and --spec: give one");
    spec::EvaluateSpec s;
    if (!from.empty()) LoadResult(from, &s);
    std::set<std::string> given;
    flags.Apply(&s, &given);
    s.plant.Normalize();
    const Controller controller = BuildController(s);
    Options options = BuildOptions(s);
    options.dt_source = flags.Given("dt")     ? "given (--dt)"
                        : !from.empty()       ? "from --from " + from
                        : flags.Given("spec") ? "from the spec"
                                              : "pidlab's default, not chosen (give --dt)";
    CheckLoop(s, &options);
    PrepareOutputDir(out, "--out");
    GeneratedCode code;
    try {
      code = Generate(options, controller);
    } catch (const std::invalid_argument& e) {
      throw BadInput(e.what());
    }
    const std::string header = out + "/pidlab_pid.h", source = out + "/pidlab_pid.c";
    // Both files or neither: a header beside a source of another run would
    // compile into a controller nobody generated.
    if (autotune) {
      const std::string relay_header = out + "/pidlab_relay.h", relay_source = out + "/pidlab_relay.c";
      Require(io::WriteFiles({{header, code.header},
                              {source, code.source},
                              {relay_header, code.relay_header},
                              {relay_source, code.relay_source}}));
      std::cout << "wrote " << header << ", " << source << ", " << relay_header << " and " << relay_source
                << " (" << scalar << ")\n";
      return 0;
    }
    Require(io::WriteFiles({{header, code.header}, {source, code.source}}));
    std::cout << "wrote " << header << " and " << source << " (" << scalar << ")\n";
    if (!pil_core.empty()) return BuildPil(code, core);
    return 0;
  }

  // --pil: the firmware beside the module, and pil.json for pidlab launch
  // --controller pil:OUT and pidlab-controller-pil.
  int BuildPil(const GeneratedCode& code, pil::Core core) const {
    pil::FirmwareBuild build;
    Require(pil::BuildFirmware(code, core, out, pil::Toolchain{}, &build));
    const nlohmann::json j = {{"elf", build.elf},
                              {"core", pil::ToString(core)},
                              {"machine", pil::QemuMachine(core)},
                              {"scalar", scalar},
                              {"text_bytes", build.text},
                              {"data_bytes", build.data},
                              {"bss_bytes", build.bss},
                              {"stack_reserved_bytes", build.stack_reserved},
                              {"command", build.command}};
    Require(io::WriteFiles({{out + "/pil.json", j.dump(2) + "\n"}}));
    std::cout << "built " << build.elf << " for " << (core == pil::Core::kM3 ? "Cortex-M3" : "Cortex-M4F")
              << " (QEMU " << pil::QemuMachine(core) << "): text " << build.text << ", data " << build.data
              << ", bss " << build.bss << " bytes, stack " << build.stack_reserved << " reserved\n";
    return 0;
  }
};

}  // namespace
std::function<int()> RegisterExport(CLI::App* app) { return RegisterCommand<ExportCommand>(app); }

}  // namespace pidlab::cli
