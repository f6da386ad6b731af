#pragma once
// Processor in the loop (docs/pil.md): the exported controller built for a
// Cortex-M3 or Cortex-M4F with arm-none-eabi-gcc (a minimal startup, no OS),
// booted under qemu-system-arm on an MPS2 board, and stepped over its UART0
// with framed, CRC-checked messages (firmware/pil_protocol.h). Every call
// that waits has a deadline; a wrong frame, a silence past the deadline or
// QEMU's exit is a Status naming it, and the destructor stops QEMU and reaps
// it.

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>

#include "pidlab/controller/pid.h"
#include "pidlab/controller_export/export.h"
#include "pidlab/spec/status.h"

namespace pidlab::pil {

enum class Core { kM3, kM4F };
/// m3 | m4f
bool ParseCore(const std::string& text, Core* core);
std::string ToString(Core core);
/// The QEMU machine: mps2-an385 (Cortex-M3) or mps2-an386 (Cortex-M4F).
const char* QemuMachine(Core core);

struct Toolchain {
  std::string gcc = "arm-none-eabi-gcc";
  std::string size = "arm-none-eabi-size";
  std::string qemu = "qemu-system-arm";
  /// Empty when all three run; else one line naming what is missing and how
  /// to install it (scripts/install-deps.sh --pil).
  std::string Missing() const;
};

/// The firmware in `dir`: pil.elf, its sections' sizes, and the command that
/// built it.
struct FirmwareBuild {
  std::string elf;
  long text = 0, data = 0, bss = 0;
  long stack_reserved = 0;  ///< the linker script's stack, bytes
  std::string command;
};

/// Writes the generated module (`code`, any scalar) and the firmware's
/// sources into `dir` (created if missing) and builds dir/pil.elf for `core`.
Status BuildFirmware(const controller_export::GeneratedCode& code, Core core, const std::string& dir,
                     const Toolchain& toolchain, FirmwareBuild* build);

/// What the firmware says of itself (PIL_INFO).
struct FirmwareInfo {
  controller_export::Scalar scalar = controller_export::Scalar::kDouble;
  int core = 3;  ///< 3 or 4
  int q_bits = 0;
  double input_full_scale = 1.0, output_full_scale = 1.0;
};

/// One step's answer.
struct StepReply {
  double u = 0.0;      ///< in the loop's units
  int status = 0;      ///< pidlab_pid_status
  uint32_t ticks = 0;  ///< SysTick ticks of pidlab_pid_step (25 MHz; 40 instructions each under -icount)
};

class Firmware {
 public:
  struct Options {
    std::string elf;
    Core core = Core::kM3;
    double deadline_s = 2.0;  ///< the longest wait for an answer, > 0
    Toolchain toolchain;
  };
  /// Boots QEMU with the image and asks for PIL_INFO within the deadline.
  static Status Boot(const Options& options, std::unique_ptr<Firmware>* out);
  ~Firmware();
  Firmware(const Firmware&) = delete;
  Firmware& operator=(const Firmware&) = delete;

  const FirmwareInfo& info() const { return info_; }
  /// pidlab_pid_init on the target; *init_status its pidlab_pid_status.
  Status Configure(const PidGains& gains, const PidOptions& pid, double setpoint_weight_b,
                   double setpoint_weight_c, int* init_status);
  /// One pidlab_pid_step: r and y as pidlab-controller-c passes them (rounded
  /// to the grid in fixed point, converted to float in float).
  Status Step(double r, double y, StepReply* reply);
  /// The stack's painted high-water mark and its size, bytes.
  Status Stats(uint32_t* stack_used, uint32_t* stack_size);
  /// Sends raw bytes (tests: a damaged frame).
  Status SendRaw(const std::string& bytes);
  /// QEMU's process id (tests).
  pid_t qemu_pid() const { return qemu_; }

 private:
  Firmware() = default;
  Status Send(uint8_t type, const std::string& payload);
  Status Receive(uint8_t want, std::string* payload);
  Status ReadExact(uint8_t* p, std::size_t n, double deadline);
  Status Exited(const std::string& waiting_for);

  Options options_;
  FirmwareInfo info_;
  pid_t qemu_ = -1;
  int to_fw_ = -1, from_fw_ = -1;
  std::string stderr_path_;
};

}  // namespace pidlab::pil
