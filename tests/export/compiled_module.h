#pragma once
// A generated controller compiled by the C compiler into a shared object and
// loaded with dlopen, behind tests/export/shim_*.c's double interface.

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

#include "pidlab/controller_export/export.h"

namespace pidlab::controller_export {

struct ShimConfig {
  double kp = 0, ki = 0, kd = 0, tf = 0, b = 1, c = 1, dt_s = 1e-3;
  int has_output_min = 0;
  double output_min = 0;
  int has_output_max = 0;
  double output_max = 0;
  int anti_windup = 1;
  double back_calculation_gain = 1;
  int integral = 0;
  double setpoint_filter_s = 0;
};

class CompiledModule {
 public:
  /// Writes `code` and `shim` (a file of tests/export/) to a fresh
  /// directory, compiles them with `cc` at C99 and -Werror, loads them.
  CompiledModule(const GeneratedCode& code, const std::string& shim, const std::string& extra_flags = "") {
    char dir_template[] = "/tmp/pidlab_export_test_XXXXXX";
    if (!mkdtemp(dir_template)) throw std::runtime_error("mkdtemp");
    dir_ = dir_template;
    std::ofstream(dir_ + "/pidlab_pid.h") << code.header;
    std::ofstream(dir_ + "/pidlab_pid.c") << code.source;
    std::string relay;  // --autotune: the relay and its shim
    if (!code.relay_source.empty()) {
      std::ofstream(dir_ + "/pidlab_relay.h") << code.relay_header;
      std::ofstream(dir_ + "/pidlab_relay.c") << code.relay_source;
      relay = " " + dir_ + "/pidlab_relay.c " + std::string(PIDLAB_EXPORT_TEST_DIR) + "/shim_relay.c";
    }
    const std::string so = dir_ + "/module.so";
    const std::string command = std::string(PIDLAB_TEST_CC) +
                                " -std=c99 -O2 -fPIC -shared -ffp-contract=off -Wall -Wextra -Wconversion "
                                "-Wsign-conversion -Werror " +
                                extra_flags + " -I" + dir_ + " " + dir_ + "/pidlab_pid.c " + shim + relay +
                                " -lm -o " + so + " 2>" + dir_ + "/cc.log";
    if (std::system(command.c_str()) != 0) {
      std::ifstream log(dir_ + "/cc.log");
      throw std::runtime_error("cc failed: " + command + "\n" +
                               std::string(std::istreambuf_iterator<char>(log), {}));
    }
    handle_ = dlopen(so.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) throw std::runtime_error(dlerror());
    Load(&new_, "shim_new");
    Load(&new_tuned_, "shim_new_tuned");
    Load(&free_, "shim_free");
    Load(&step_, "shim_step");
    Load(&set_manual_, "shim_set_manual");
    Load(&set_auto_, "shim_set_auto");
    Load(&set_gains_, "shim_set_gains");
    Load(&set_weights_, "shim_set_setpoint_weights");
    Load(&set_sample_time_, "shim_set_sample_time");
    // Fixed point only (shim_fixed.c).
    quantize_input_ = reinterpret_cast<double (*)(double)>(dlsym(handle_, "shim_quantize_input"));
    quantize_output_ = reinterpret_cast<double (*)(double)>(dlsym(handle_, "shim_quantize_output"));
    output_lsb_ = reinterpret_cast<double (*)()>(dlsym(handle_, "shim_output_lsb"));
    step_raw_ = reinterpret_cast<int (*)(void*, long, long, long*)>(dlsym(handle_, "shim_step_raw"));
    // The relay only (shim_relay.c).
    relay_new_ =
        reinterpret_cast<void* (*)(void*, const double*, int, int)>(dlsym(handle_, "shim_relay_new"));
    relay_free_ = reinterpret_cast<void (*)(void*)>(dlsym(handle_, "shim_relay_free"));
    relay_step_ =
        reinterpret_cast<double (*)(void*, double, double, double)>(dlsym(handle_, "shim_relay_step"));
    relay_phase_ = reinterpret_cast<int (*)(void*)>(dlsym(handle_, "shim_relay_phase"));
    relay_cycle_count_ = reinterpret_cast<long (*)(void*)>(dlsym(handle_, "shim_relay_cycle_count"));
    relay_cycle_ = reinterpret_cast<int (*)(void*, long, double*)>(dlsym(handle_, "shim_relay_cycle"));
  }
  ~CompiledModule() {
    if (handle_) dlclose(handle_);
    std::system(("rm -rf " + dir_).c_str());
  }
  CompiledModule(const CompiledModule&) = delete;
  CompiledModule& operator=(const CompiledModule&) = delete;

  void* (*new_)(const ShimConfig*) = nullptr;
  void* (*new_tuned_)() = nullptr;
  void (*free_)(void*) = nullptr;
  int (*step_)(void*, double, double, double*) = nullptr;
  int (*set_manual_)(void*, double) = nullptr;
  void (*set_auto_)(void*) = nullptr;
  int (*set_gains_)(void*, double, double, double, double) = nullptr;
  int (*set_weights_)(void*, double, double) = nullptr;
  int (*set_sample_time_)(void*, double) = nullptr;
  double (*quantize_input_)(double) = nullptr;
  double (*quantize_output_)(double) = nullptr;
  double (*output_lsb_)() = nullptr;
  int (*step_raw_)(void*, long, long, long*) = nullptr;
  void* (*relay_new_)(void*, const double*, int, int) = nullptr;
  void (*relay_free_)(void*) = nullptr;
  double (*relay_step_)(void*, double, double, double) = nullptr;
  int (*relay_phase_)(void*) = nullptr;
  long (*relay_cycle_count_)(void*) = nullptr;
  int (*relay_cycle_)(void*, long, double*) = nullptr;

 private:
  template <typename F>
  void Load(F* f, const char* name) {
    *f = reinterpret_cast<F>(dlsym(handle_, name));
    if (!*f) throw std::runtime_error(std::string("no symbol ") + name);
  }
  std::string dir_;
  void* handle_ = nullptr;
};

}  // namespace pidlab::controller_export
