// pidlab: one executable, one subcommand per job (evaluate, tune, launch,
// replay, plot, report). Each subcommand lives in its own cmd_*.cc file and
// registers itself; this file only dispatches and applies the exit convention.

#include <iostream>

#include "cli_common.h"

int main(int argc, char** argv) {
  CLI::App app{"pidlab: PID tuning by Nelder-Mead, evaluated exactly and run as a distributed LCM system"};
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (const auto& command : pidlab::cli::Registry()) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    actions.emplace_back(sub, command.factory(sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string where = "pidlab";
    for (const auto* sub : app.get_subcommands()) where += " " + sub->get_name();
    std::cerr << where << ": error: " << e.what() << "\n";
    return 2;
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    try {
      return action();
    } catch (const pidlab::cli::BadInput& e) {
      std::cerr << "pidlab " << sub->get_name() << ": error: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "pidlab " << sub->get_name() << ": failed: " << e.what() << "\n";
      return 1;
    }
  }
  return 2;
}
