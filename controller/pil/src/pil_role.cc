// The firmware as the trio's controller (pil_role.h).

#include "pidlab/pil/pil_role.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pidlab::pil {

FirmwarePid::FirmwarePid(std::unique_ptr<Firmware> firmware, double core_clock_hz, transport::LogFn log)
    : firmware_(std::move(firmware)), log_(std::move(log)) {
  cost_.core_clock_hz = core_clock_hz;
}

Status FirmwarePid::Configure(const transport::EpisodeSpec& spec, bool* fatal) {
  *fatal = true;
  PidOptions pid = PidOptionsAt(spec.pid, spec.dt_s);
  // As pidlab-controller-c passes the message's filter to the module: the
  // configured derivative_filter_s itself (controller_role_c.c).
  pid.derivative_filter_s = spec.pid.derivative_filter_s;
  int init = 0;
  if (const Status st = firmware_->Configure(spec.gains, pid, spec.pid.setpoint_weight_b,
                                             spec.pid.setpoint_weight_c, &init);
      !st.ok())
    return st;
  dt_s_ = spec.dt_s;
  if (init != 0) {
    *fatal = false;
    return Status::InvalidInput("the firmware's module refused the configuration (pidlab_pid_init status " +
                                std::to_string(init) + ")");
  }
  return Status::Ok();
}

Status FirmwarePid::Step(double r, double y, double* u, PidStatus* status) {
  const bool fixed = firmware_->info().q_bits != 0;
  if (fixed && !std::isfinite(y)) {  // as pidlab-controller-c: no step, u 0, invalid input
    *u = 0.0;
    *status = PidStatus::kInvalidInput;
    return Status::Ok();
  }
  StepReply reply;
  if (const Status st = firmware_->Step(r, y, &reply); !st.ok()) return st;
  *u = reply.u;
  *status = reply.status == 0   ? PidStatus::kOk
            : reply.status == 1 ? PidStatus::kSaturated
                                : PidStatus::kInvalidInput;
  const long instructions = 40L * static_cast<long>(reply.ticks);
  ++cost_.steps;
  sum_instructions_ += static_cast<double>(instructions);
  cost_.mean_instructions = sum_instructions_ / static_cast<double>(cost_.steps);
  cost_.max_instructions = std::max(cost_.max_instructions, instructions);
  if (cost_.core_clock_hz > 0.0 && dt_s_ > 0.0) {
    const double fraction = static_cast<double>(instructions) / cost_.core_clock_hz / dt_s_;
    cost_.worst_fraction_of_dt = std::max(cost_.worst_fraction_of_dt, fraction);
    if (fraction > 1.0 && ++cost_.over_deadline == 1 && log_) {
      std::ostringstream os;
      os << "deadline: step " << cost_.steps - 1 << " took " << instructions << " instructions, "
         << 1e6 * static_cast<double>(instructions) / cost_.core_clock_hz << " us at "
         << cost_.core_clock_hz / 1e6 << " MHz (one a cycle, emulated), over dt = " << 1e6 * dt_s_ << " us";
      log_(os.str());
    }
  }
  return Status::Ok();
}

}  // namespace pidlab::pil
