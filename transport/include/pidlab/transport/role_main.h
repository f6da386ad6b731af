#pragma once
// The shared `main` of pidlab-plant, pidlab-controller and pidlab-disturbance:
// flags -> options -> validate -> serve until SIGINT/SIGTERM.

#include <functional>
#include <memory>
#include <string>

#include "pidlab/transport/role.h"

namespace pidlab::transport {

using RoleFactory = std::function<std::unique_ptr<Role>(Transport* transport, LogFn log, bool verbose)>;

/// Exit status: 0 after a signal, 2 for bad flags (one line on stderr),
/// 1 if LCM cannot start or fails.
int RoleMain(int argc, char** argv, const std::string& program, const std::string& description,
             const RoleFactory& factory);

}  // namespace pidlab::transport
