// pidlab: one executable, one subcommand per job. The table below is the
// whole command line; each subcommand lives in its own cmd_*.cc. This file
// only dispatches and applies the exit convention (README.md, "Exit status
// and limits"): 2 for bad input, anything the user typed (an unwritable output
// path included), 1 for a runtime failure; either way exactly one line on
// stderr, at most ~300 characters.

#include <algorithm>
#include <cstdlib>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "did_you_mean.h"

namespace {

struct Command {
  const char* name;
  const char* description;
  std::function<int()> (*register_flags)(CLI::App* app);
};

// The sanitised tree's pidlab (tools/CMakeLists.txt) holds only the
// commands the hostile tests run on it: evaluate, launch, replay and serve
// (and version).
const Command kCommands[] = {
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
    {"autotune", "relay autotune on the running trio: Ku, Pu, a FOPDT model, a design, a verified step",
     pidlab::cli::RegisterAutotune},
    {"batch", "the AMIGO test batch: AMIGO's PID against pidlab's optimum on P1-P9",
     pidlab::cli::RegisterBatch},
#endif
    {"evaluate", "evaluate one gain set (IAE, poles, step metrics)", pidlab::cli::RegisterEvaluate},
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
    {"export", "the discrete PID as a dependency-free C99 module (pidlab_pid.h, pidlab_pid.c)",
     pidlab::cli::RegisterExport},
    {"identify", "fit a process model (p1d, p2d, p2du, p1di, p2dz, auto) to t, u, y of a CSV or a log",
     pidlab::cli::RegisterIdentify},
    {"linearize", "transfer function of a nonlinear plant's linearisation (stepper_nonlinear)",
     pidlab::cli::RegisterLinearize},
#endif
    {"launch", "start the LCM process trio (plant, controller, disturbance)", pidlab::cli::RegisterLaunch},
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
    {"plot", "PNG figures of y, e, u, n from an evaluation or an LCM log", pidlab::cli::RegisterPlot},
#endif
    {"replay", "read an LCM log: episodes, IAE, completeness, --redrive", pidlab::cli::RegisterReplay},
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
    {"report", "regenerate the paper's tables and figures (report.md + PNGs)", pidlab::cli::RegisterReport},
#endif
    {"serve", "the tuning workbench in the browser (HTTP and WebSocket server)", pidlab::cli::RegisterServe},
#ifndef PIDLAB_HOSTILE_COMMANDS_ONLY
    {"tune", "tune PID gains (Nelder-Mead, paper-nm, ZN, GA, PSO-GSA) + Ceres check",
     pidlab::cli::RegisterTune},
#endif
    {"version", "print the version and the git commit this pidlab was built from",
     pidlab::cli::RegisterVersion},
};

// The message of an error as one printable line of at most 270 characters
// (after "pidlab <command>: error: "), whatever the exception carried.
std::string OneLine(const std::string& message) { return pidlab::cli::Truncate(message, 270); }

/// Every name `app` knows its options by, as typed: "--plant", "-v".
std::vector<std::string> OptionNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    for (const std::string& name : option->get_snames()) names.push_back("-" + name);
  }
  return names;
}

/// " (did you mean --plant?)" for the closest of `names` to `typed`, else
/// " (<help>)".
std::string Hint(const std::string& typed, const std::vector<std::string>& names, const std::string& help) {
  const std::string closest = pidlab::cli::ClosestName(typed, names);
  return closest.empty() ? " (" + help + ")" : " (did you mean " + closest + "?)";
}

/// An option as typed, without its "=value".
std::string OptionName(const std::string& token) { return token.substr(0, token.find('=')); }

/// Whether `token` is an option CLI11 left over ("--plnat", "-x=1"), not a
/// value ("stepper", "-1.5", "-").
bool LooksLikeOption(const std::string& token) {
  if (token.size() < 2 || token[0] != '-') return false;
  char* end = nullptr;
  std::strtod(token.c_str(), &end);
  return *end != '\0';
}

/// The error for args[1] when it names neither a subcommand ("pidlab tunr")
/// nor an option of pidlab itself ("pidlab --verison"), else "": CLI11 would
/// only say that a subcommand is required.
std::string UnknownFirstWord(const CLI::App& app, const std::vector<std::string>& args) {
  if (args.size() < 2 || args[1].empty() || args[1] == "--") return "";
  const std::string& word = args[1];
  if (LooksLikeOption(word)) {
    const std::vector<std::string> options = OptionNames(app);
    const std::string name = OptionName(word);
    if (std::find(options.begin(), options.end(), name) != options.end()) return "";
    return "unknown option " + pidlab::cli::Quote(name) + Hint(name, options, "pidlab --help");
  }
  std::vector<std::string> commands;
  for (const Command& command : kCommands) {
    if (word == command.name) return "";
    commands.push_back(command.name);
  }
  std::string list;
  for (const std::string& command : commands) list += (list.empty() ? "" : ", ") + command;
  return pidlab::cli::Quote(word) + " is not a subcommand" + Hint(word, commands, list + "; pidlab --help");
}

/// The error for the first option of `args` that `where` does not know and
/// CLI11 left over ("pidlab tune --plnat stepper"), else "": a stray value
/// keeps CLI11's "not expected", a value that starts with '-' was taken by
/// its option, and what follows "--" is a command's own ("launch -- CMD").
std::string UnknownOption(const CLI::App& app, const CLI::App& where, const std::string& where_name,
                          const std::vector<std::string>& args) {
  const std::vector<std::string> options = OptionNames(where);
  const std::vector<std::string> left_over = app.remaining(true);
  for (std::size_t i = 1; i < args.size() && args[i] != "--"; ++i) {
    const std::string& token = args[i];
    if (!LooksLikeOption(token) || std::find(left_over.begin(), left_over.end(), token) == left_over.end())
      continue;
    const std::string name = OptionName(token);
    if (std::find(options.begin(), options.end(), name) != options.end()) continue;
    return "unknown option " + pidlab::cli::Quote(name) + Hint(name, options, where_name + " --help");
  }
  return "";
}

/// CLI11 2.1 loses the "--" that follows an option with an optional value
/// ("launch --realtime -- CMD", "launch --realtime 2 -- CMD"), so CMD's own
/// flags become the subcommand's. Before the first "--", such an option is
/// given its value with '=': "--realtime=2", or "--realtime=<its default>"
/// when "--" or another option follows.
void JoinOptionalValues(CLI::App* sub, std::vector<std::string>* args) {
  for (std::size_t i = 2; i < args->size() && (*args)[i] != "--"; ++i) {
    std::string& token = (*args)[i];
    if (token.size() < 3 || token.compare(0, 2, "--") != 0 || token.find('=') != std::string::npos) continue;
    const CLI::Option* option = nullptr;
    for (const CLI::Option* o : sub->get_options())
      if (o->check_name(token)) option = o;
    if (!option || option->get_expected_min() != 0 || option->get_expected_max() != 1) continue;
    const bool next_is_value = i + 1 < args->size() && !(*args)[i + 1].empty() && (*args)[i + 1][0] != '-';
    if (next_is_value) {
      token += "=" + (*args)[i + 1];
      args->erase(args->begin() + static_cast<std::ptrdiff_t>(i) + 1);
    } else if (i + 1 < args->size() && (*args)[i + 1] == "--") {
      token += "=" + option->get_default_str();
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pidlab: PID tuning by Nelder-Mead, evaluated exactly and run as a distributed LCM system"};
  app.require_subcommand(1);
  app.set_version_flag("--version", pidlab::cli::VersionLine,
                       "print the version and the git commit this pidlab was built from");
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  for (const Command& command : kCommands) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    actions.emplace_back(sub, command.register_flags(sub));
  }
  std::vector<std::string> args(argv, argv + argc);
  const std::string unknown = UnknownFirstWord(app, args);
  if (!unknown.empty()) {
    std::cerr << "pidlab: error: " << OneLine(unknown) << "\n";
    return 2;
  }
  for (auto& [sub, action] : actions)
    if (args.size() > 1 && args[1] == sub->get_name()) JoinOptionalValues(sub, &args);
  try {
    // CLI11 takes the arguments in reverse order when given a vector.
    app.name(args[0]);
    app.parse(std::vector<std::string>(args.rbegin(), args.rend() - 1));
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string where = "pidlab";
    const CLI::App* where_app = &app;
    for (const auto* sub : app.get_subcommands()) {
      where += " " + sub->get_name();
      where_app = sub;
    }
    // A mistyped option is named first: it is often why a required one is
    // missing ("--plnat stepper": "--plant is required").
    const std::string unknown_option = UnknownOption(app, *where_app, where, args);
    std::cerr << where << ": error: " << OneLine(unknown_option.empty() ? e.what() : unknown_option) << "\n";
    return 2;
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    // The counted notes of a run come before its result's end or its last line.
    try {
      const int status = action();
      pidlab::cli::FlushRunNotes();
      return status;
    } catch (const pidlab::cli::BadInput& e) {
      pidlab::cli::FlushRunNotes();
      std::cerr << "pidlab " << sub->get_name() << ": error: " << OneLine(e.what()) << "\n";
      return 2;
    } catch (const std::exception& e) {
      pidlab::cli::FlushRunNotes();
      std::cerr << "pidlab " << sub->get_name() << ": failed: " << OneLine(e.what()) << "\n";
      return 1;
    }
  }
  return 2;
}
