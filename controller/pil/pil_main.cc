// pidlab-controller-pil: the trio's controller role with the PID on an
// emulated Cortex-M (docs/pil.md). Boots `--firmware` (pidlab pil's pil.elf)
// under qemu-system-arm and hands it every plant output over its UART; the
// rest is pidlab-controller's (loss recovery, auth, logging). A wrong frame,
// a silence past --deadline or QEMU's exit stops it with one line, exit 1,
// and QEMU is reaped.

#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "pidlab/controller/controller_role.h"
#include "pidlab/pil/pil_role.h"
#include "pidlab/transport/role_main.h"

int main(int argc, char** argv) {
  using namespace pidlab;
  std::string elf, core_text = "m3", report;
  double deadline_s = 2.0, core_clock_hz = 0.0;
  std::shared_ptr<pil::FirmwarePid> firmware;
  pil::Core core = pil::Core::kM3;
  const auto flags = [&](CLI::App* app) {
    app->add_option("--firmware", elf, "the firmware image: pidlab pil's DIR/pil.elf")->required();
    app->add_option("--core", core_text, "m3 (QEMU mps2-an385) or m4f (mps2-an386): the image's core")
        ->capture_default_str();
    app->add_option("--deadline", deadline_s, "the longest wait for the firmware's answer, s")
        ->capture_default_str();
    app->add_option("--core-clock-hz", core_clock_hz,
                    "flag steps slower than dt at this clock, one instruction a cycle (0: no check)")
        ->capture_default_str();
    app->add_option("--report", report, "at exit, write the steps' cost and the stack as JSON to this file");
  };
  const auto num = [](double v) {
    std::ostringstream os;
    os << v;
    return os.str();
  };
  const auto check = [&]() -> std::string {
    if (!pil::ParseCore(core_text, &core)) return "--core '" + core_text + "' is not m3 or m4f";
    if (!(deadline_s > 0.0) || !std::isfinite(deadline_s))
      return "--deadline " + num(deadline_s) + " must be > 0 and finite";
    if (!(core_clock_hz >= 0.0) || !std::isfinite(core_clock_hz))
      return "--core-clock-hz " + num(core_clock_hz) + " must be >= 0 and finite";
    return "";
  };
  const int status = transport::RoleMain(
      argc, argv, "pidlab-controller-pil",
      "pidlab-controller-pil: the trio's controller with the PID on an emulated Cortex-M (docs/pil.md)",
      [&](transport::Transport* t, transport::LogFn log, bool verbose) -> std::unique_ptr<transport::Role> {
        pil::Firmware::Options o;
        o.elf = elf;
        o.core = core;
        o.deadline_s = deadline_s;
        std::unique_ptr<pil::Firmware> fw;
        if (const Status st = pil::Firmware::Boot(o, &fw); !st.ok()) {
          std::cerr << "pidlab-controller-pil: failed: " << st.message() << "\n";
          return nullptr;
        }
        if (verbose)
          log("firmware " + elf + " booted on " + pil::QemuMachine(core) + ": " +
              controller_export::ToString(fw->info().scalar));
        firmware = std::make_shared<pil::FirmwarePid>(std::move(fw), core_clock_hz, log);
        return std::make_unique<controller::ControllerRole>(t, log, verbose, firmware);
      },
      nullptr, flags, check);
  if (firmware && !report.empty()) {
    const pil::StepCost& c = firmware->cost();
    uint32_t used = 0, size = 0;
    const Status st = status == 0 ? firmware->firmware().Stats(&used, &size) : Status::Ok();
    nlohmann::json j = {
        {"firmware", elf},
        {"core", pil::ToString(core)},
        {"machine", pil::QemuMachine(core)},
        {"scalar", controller_export::ToString(firmware->firmware().info().scalar)},
        {"steps", c.steps},
        {"instructions_per_step", {{"mean", c.mean_instructions}, {"max", c.max_instructions}}},
        {"emulated",
         "QEMU -icount shift=0: 1 instruction = 1 ns of virtual time; SysTick counts 25 MHz, so "
         "instruction counts are multiples of 40; not silicon timing"},
        {"stack_bytes", st.ok() && status == 0 ? nlohmann::json(used) : nlohmann::json(nullptr)},
        {"stack_reserved", st.ok() && status == 0 ? nlohmann::json(size) : nlohmann::json(nullptr)},
        {"deadline",
         {{"core_clock_hz", c.core_clock_hz},
          {"steps_over_dt", c.over_deadline},
          {"worst_fraction_of_dt", c.worst_fraction_of_dt}}}};
    std::ofstream(report) << j.dump(2) << "\n";
    if (!st.ok()) std::cerr << "pidlab-controller-pil: the stack's mark: " << st.message() << "\n";
  }
  return status;
}
