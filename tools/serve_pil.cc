// The workbench's processor-in-the-loop costs (docs/pil.md, docs/workbench.md):
// {"type": "pil_cost", "spec": SPEC} builds the design's exported controller
// for every scalar (double, float, q31, q15) and core (Cortex-M3, Cortex-M4F)
// as `pidlab export --pil` does, boots each under QEMU and steps it through
// the first steps of the design's own sampled loop (its r and y, computed
// here), on a thread; the table is posted on the connection.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "cli_common.h"
#include "export_spec.h"
#include "pidlab/pil/firmware.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/tune/problem.h"
#include "serve_requests.h"

namespace pidlab::cli {
namespace {

constexpr long kPilCostSteps = 200;  // of the loop, per scalar and core

nlohmann::json CostRow(const controller_export::GeneratedCode& code, pil::Core core,
                       const controller_export::Controller& c,
                       const std::vector<evaluation::SampledStep>& steps) {
  nlohmann::json row = {{"core", pil::ToString(core)}, {"machine", pil::QemuMachine(core)}};
  char dir_template[] = "/tmp/pidlab_pil_XXXXXX";
  if (!mkdtemp(dir_template)) return row.update({{"error", "no temporary folder"}}), row;
  const std::string dir = dir_template;
  const auto fail = [&](const std::string& why) {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
    row["error"] = why;
    return row;
  };
  pil::FirmwareBuild build;
  if (const Status st = pil::BuildFirmware(code, core, dir, pil::Toolchain{}, &build); !st.ok())
    return fail(st.message());
  std::unique_ptr<pil::Firmware> fw;
  pil::Firmware::Options o;
  o.elf = build.elf;
  o.core = core;
  if (const Status st = pil::Firmware::Boot(o, &fw); !st.ok()) return fail(st.message());
  PidOptions pid = c.pid;
  pid.derivative_filter_s = EffectiveDerivativeFilter(c.gains, c.pid);
  int init = 0;
  if (const Status st = fw->Configure(c.gains, pid, c.setpoint_weight_b, c.setpoint_weight_c, &init);
      !st.ok())
    return fail(st.message());
  if (init != 0)
    return fail("the module refused the design (pidlab_pid_init status " + std::to_string(init) + ")");
  double sum = 0.0;
  long max = 0, n = 0;
  for (const evaluation::SampledStep& s : steps) {
    if (n >= kPilCostSteps || !std::isfinite(s.y)) break;
    pil::StepReply reply;
    if (const Status st = fw->Step(s.r, s.y, &reply); !st.ok()) return fail(st.message());
    const long instructions = 40L * static_cast<long>(reply.ticks);
    sum += static_cast<double>(instructions);
    max = std::max(max, instructions);
    ++n;
  }
  uint32_t stack = 0, reserved = 0;
  if (const Status st = fw->Stats(&stack, &reserved); !st.ok()) return fail(st.message());
  fw.reset();  // QEMU stopped and reaped
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  row.update({{"steps", n},
              {"instructions_mean", n > 0 ? sum / static_cast<double>(n) : 0.0},
              {"instructions_max", max},
              {"stack_bytes", stack},
              {"text_bytes", build.text},
              {"data_bss_bytes", build.data + build.bss}});
  return row;
}

nlohmann::json PilCost(const nlohmann::json& spec_json) {
  nlohmann::json reply = {{"type", "pil_cost_result"}};
  if (const std::string missing = pil::Toolchain{}.Missing(); !missing.empty()) {
    reply["error"] = missing;
    return reply;
  }
  spec::EvaluateSpec s;
  tune::BuildOptions build;
  if (const Status st = spec::FromJson(spec_json, &s, &build.given); !st.ok())
    return reply.update({{"error", st.message()}}), reply;
  s.plant.Normalize();
  controller_export::Controller c;
  std::string error;
  if (!ExportController(s, spec::NameStyle::kKey, &c, &error)) return reply.update({{"error", error}}), reply;
  // The design's own loop, sampled at its dt: the r and y each firmware gets.
  tune::EvaluationProblem problem;
  if (const Status st = tune::BuildEvaluation(s, build, &problem); !st.ok())
    return reply.update({{"error", st.message()}}), reply;
  if (problem.loop.loop != evaluation::LoopKind::kSampled)
    return reply.update({{"error", "the PIL costs need the sampled loop (loop: sampled, dt)"}}), reply;
  tune::EvaluationRunOptions run;
  run.what.record_trajectory = true;
  run.monte_carlo = false;
  tune::EvaluationResult r;
  if (const Status st = tune::RunEvaluation(problem, run, &r); !st.ok())
    return reply.update({{"error", st.message()}}), reply;
  const std::vector<evaluation::SampledStep>& steps = r.evaluation.trajectory;
  // Fixed point's declared input range: twice the largest |r| or |y| of the loop.
  double range = 0.0;
  for (const evaluation::SampledStep& k : steps)
    if (std::isfinite(k.y)) range = std::max({range, std::abs(k.r), std::abs(k.y)});
  range = range > 0.0 ? 2.0 * range : 1.0;
  // Fixed point needs output limits: a design without them gets twice the
  // largest |u| of its loop (said in the reply).
  controller_export::Controller fixed = c;
  const bool limited = std::isfinite(c.pid.output_min) && std::isfinite(c.pid.output_max);
  if (!limited) {
    double u_max = 0.0;
    for (const evaluation::SampledStep& k : steps)
      if (std::isfinite(k.u)) u_max = std::max(u_max, std::abs(k.u));
    u_max = u_max > 0.0 ? 2.0 * u_max : 1.0;
    fixed.pid.output_min = -u_max;
    fixed.pid.output_max = u_max;
    reply["fixed_point_output_limits"] = {-u_max, u_max};
  }
  nlohmann::json rows = nlohmann::json::array();
  for (controller_export::Scalar scalar :
       {controller_export::Scalar::kDouble, controller_export::Scalar::kFloat,
        controller_export::Scalar::kQ31, controller_export::Scalar::kQ15}) {
    controller_export::Options o;
    o.scalar = scalar;
    o.input_min = -range;
    o.input_max = range;
    o.pidlab_version = PIDLAB_VERSION;
    controller_export::GeneratedCode code;
    std::string refused;
    const bool is_fixed =
        scalar == controller_export::Scalar::kQ31 || scalar == controller_export::Scalar::kQ15;
    const controller_export::Controller& used = is_fixed ? fixed : c;
    try {
      code = controller_export::Generate(o, used);
    } catch (const std::invalid_argument& e) {
      refused = e.what();
    }
    for (pil::Core core : {pil::Core::kM3, pil::Core::kM4F}) {
      nlohmann::json row = refused.empty()
                               ? CostRow(code, core, used, steps)
                               : nlohmann::json{{"core", pil::ToString(core)}, {"error", refused}};
      row["scalar"] = controller_export::ToString(scalar);
      rows.push_back(row);
    }
  }
  reply["rows"] = rows;
  reply["input_range"] = {-range, range};
  reply["emulated"] =
      "QEMU -icount shift=0: 1 instruction = 1 ns of virtual time, counted by SysTick at 25 MHz (multiples "
      "of "
      "40); not silicon timing";
  return reply;
}

}  // namespace

server::Reply AnswerPilCost(const nlohmann::json& request,
                            const std::shared_ptr<server::Connection>& connection) {
  if (!connection)
    return {400, {{"error", "pil_cost runs over the WebSocket /ws, which carries its result"}}};
  if (!request.contains("spec") || !request["spec"].is_object())
    return {400, {{"error", "a pil_cost request needs a spec object"}}};
  return StartJob(request, connection, {"pil_cost", "pil_cost_result", "PIL costs"},
                  [spec = request["spec"]](const std::shared_ptr<ConnectionJob>&) { return PilCost(spec); });
}

}  // namespace pidlab::cli
