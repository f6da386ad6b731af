// Writes the double module (pidlab_pid.h, pidlab_pid.c) and the relay
// autotune (pidlab_relay.h, pidlab_relay.c) into argv[1] for
// pidlab-controller-c, which configures it from each episode's message.
#include <fstream>
#include <iostream>

#include "pidlab/controller_export/export.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: generate_module DIR\n";
    return 2;
  }
  pidlab::controller_export::Options options;
  options.plant = "any: pidlab-controller-c takes the loop from each episode's configuration";
  options.pidlab_version = PIDLAB_VERSION;
  options.autotune = true;
  const auto code = pidlab::controller_export::Generate(options, pidlab::controller_export::Controller{});
  const std::string dir = argv[1];
  std::ofstream(dir + "/pidlab_pid.h") << code.header;
  std::ofstream(dir + "/pidlab_pid.c") << code.source;
  std::ofstream(dir + "/pidlab_relay.h") << code.relay_header;
  std::ofstream(dir + "/pidlab_relay.c") << code.relay_source;
  return std::ofstream(dir + "/pidlab_relay.c", std::ios::app) ? 0 : 1;
}
