// pidlab: one executable, one subcommand per job. The table below is the
// whole command line; each subcommand lives in its own cmd_*.cc. This file
// only dispatches and applies the exit convention (README.md, "Exit status
// and limits"): 2 for bad input, anything the user typed (an unwritable output
// path included), 1 for a runtime failure; either way exactly one line on
// stderr, at most ~300 characters.

#include <iostream>

#include "cli_common.h"
#include "commands.h"

namespace {

struct Command {
  const char* name;
  const char* description;
  std::function<int()> (*register_flags)(CLI::App* app);
};

const Command kCommands[] = {
    {"evaluate", "evaluate one gain set (IAE, poles, step metrics)", pidlab::cli::RegisterEvaluate},
    {"linearize", "transfer function of a nonlinear plant's linearisation (stepper_nonlinear)",
     pidlab::cli::RegisterLinearize},
    {"launch", "start the LCM process trio (plant, controller, disturbance)", pidlab::cli::RegisterLaunch},
    {"plot", "PNG figures of y, e, u, n from an evaluation or an LCM log", pidlab::cli::RegisterPlot},
    {"replay", "read an LCM log: episodes, IAE, completeness, --redrive", pidlab::cli::RegisterReplay},
    {"report", "regenerate the paper's tables and figures (report.md + PNGs)", pidlab::cli::RegisterReport},
    {"tune", "tune PID gains (Nelder-Mead, paper-nm, ZN, GA, PSO-GSA) + Ceres check",
     pidlab::cli::RegisterTune},
};

// The message of an error as one printable line of at most 270 characters
// (after "pidlab <command>: error: "), whatever the exception carried.
std::string OneLine(const std::string& message) { return pidlab::cli::Truncate(message, 270); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pidlab: PID tuning by Nelder-Mead, evaluated exactly and run as a distributed LCM system"};
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (const Command& command : kCommands) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    actions.emplace_back(sub, command.register_flags(sub));
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
    std::cerr << where << ": error: " << OneLine(e.what()) << "\n";
    return 2;
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    try {
      return action();
    } catch (const pidlab::cli::BadInput& e) {
      std::cerr << "pidlab " << sub->get_name() << ": error: " << OneLine(e.what()) << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "pidlab " << sub->get_name() << ": failed: " << OneLine(e.what()) << "\n";
      return 1;
    }
  }
  return 2;
}
