#pragma once
// The firmware as the trio's controller (docs/pil.md): an ExternalPid over a
// booted Firmware for pidlab-controller-pil, with each step's cost.

#include <cstdint>
#include <memory>
#include <string>

#include "pidlab/controller/controller_role.h"
#include "pidlab/pil/firmware.h"

namespace pidlab::pil {

/// What the steps cost on the emulated core. Emulated figures, not silicon
/// timing: QEMU's -icount shift=0 makes one instruction one nanosecond of
/// virtual time, and the step's SysTick ticks (25 MHz) are 40 instructions
/// each, so an instruction count is a multiple of 40.
struct StepCost {
  long steps = 0;
  double mean_instructions = 0.0;
  long max_instructions = 0;
  /// Deadline: a step over dt at `core_clock_hz`, one instruction a cycle.
  double core_clock_hz = 0.0;  ///< 0: no check
  long over_deadline = 0;
  double worst_fraction_of_dt = 0.0;  ///< max instructions / clock / dt
};

class FirmwarePid : public controller::ExternalPid {
 public:
  /// `log` gets one line at the first step over the deadline (may be empty).
  FirmwarePid(std::unique_ptr<Firmware> firmware, double core_clock_hz, transport::LogFn log = {});
  Status Configure(const transport::EpisodeSpec& spec, bool* fatal) override;
  Status Step(double r, double y, double* u, PidStatus* status) override;
  const StepCost& cost() const { return cost_; }
  Firmware& firmware() { return *firmware_; }

 private:
  std::unique_ptr<Firmware> firmware_;
  StepCost cost_;
  transport::LogFn log_;
  double dt_s_ = 0.0;
  double sum_instructions_ = 0.0;
};

}  // namespace pidlab::pil
