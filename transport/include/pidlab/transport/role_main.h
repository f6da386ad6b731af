#pragma once
// The shared `main` of pidlab-plant, pidlab-controller and pidlab-disturbance:
// flags -> options -> validate -> serve until SIGINT/SIGTERM.

#include <functional>
#include <memory>
#include <string>

#include "pidlab/transport/role.h"

namespace CLI {
class App;
}

namespace pidlab::transport {

using RoleFactory = std::function<std::unique_ptr<Role>(Transport* transport, LogFn log, bool verbose)>;

/// The pacing flags of pidlab-plant (pacing.h), parsed before the factory runs.
struct RealtimeFlags {
  double factor = 0.0;  // --realtime [FACTOR] (1 without a value); 0: not paced
  int rt_priority = 0;  // --rt-priority N: SCHED_FIFO priority N; 0: normal scheduling
};

/// Exit status: 0 after a signal, 2 for bad flags (one line on stderr),
/// 1 if LCM cannot start or fails. With `realtime`, the process also takes
/// --realtime [FACTOR] and --rt-priority N; a refused SCHED_FIFO is said on
/// stderr once, and the process continues at normal priority.
///
/// `more_flags` registers a process's own flags; `check_flags` then returns
/// "" or the one line of exit 2 naming the bad value (both may be empty).
/// A factory that returns null has said why on stderr: exit 1. A role that
/// halts (Role::Halted) has said why: exit 1.
int RoleMain(int argc, char** argv, const std::string& program, const std::string& description,
             const RoleFactory& factory, RealtimeFlags* realtime = nullptr,
             const std::function<void(CLI::App*)>& more_flags = {},
             const std::function<std::string()>& check_flags = {});

}  // namespace pidlab::transport
