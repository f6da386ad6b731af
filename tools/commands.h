#pragma once
// The subcommands of `pidlab`, one per cmd_*.cc. Each registers its flags on
// `app` and returns the action to run after parsing (the exit status).

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>

namespace pidlab::cli {

std::function<int()> RegisterAutotune(CLI::App* app);
std::function<int()> RegisterEvaluate(CLI::App* app);
std::function<int()> RegisterTune(CLI::App* app);
std::function<int()> RegisterLaunch(CLI::App* app);
std::function<int()> RegisterReplay(CLI::App* app);
std::function<int()> RegisterPlot(CLI::App* app);
std::function<int()> RegisterReport(CLI::App* app);
std::function<int()> RegisterLinearize(CLI::App* app);
std::function<int()> RegisterBatch(CLI::App* app);
std::function<int()> RegisterIdentify(CLI::App* app);
std::function<int()> RegisterServe(CLI::App* app);
std::function<int()> RegisterExport(CLI::App* app);
std::function<int()> RegisterVersion(CLI::App* app);

/// The action of a command object T, made here and kept as long as the
/// action: T::Register(app) registers its flags and returns what runs.
template <typename T>
std::function<int()> RegisterCommand(CLI::App* app) {
  auto command = std::make_shared<T>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

/// "pidlab 0.2.0 (commit 4b5211fe12ab)": what `pidlab version` and
/// `pidlab --version` print.
std::string VersionLine();

}  // namespace pidlab::cli
