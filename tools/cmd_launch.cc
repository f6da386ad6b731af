// pidlab launch: flags -> LaunchOptions -> pidlab::launcher::Launcher
// (launcher/launcher.h): start the trio (and lcm-logger), run COMMAND or
// serve, check and repair the log, stop everything.

#include <csignal>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/launcher/launcher.h"

namespace pidlab::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;
void OnSignal(int sig) { g_signal = sig; }

void Note(const std::string& line) { std::cerr << "pidlab launch: " << line << "\n"; }

}  // namespace

std::function<int()> RegisterLaunch(CLI::App* app) {
  struct Flags {
    launcher::LaunchOptions options;
    bool isolated = false;
    std::vector<std::string> command;
  };
  auto flags = std::make_shared<Flags>();
  launcher::LaunchOptions& o = flags->options;
  app->description(
      "Start pidlab-plant, pidlab-controller and pidlab-disturbance (and lcm-logger with --log), wait until "
      "all "
      "are ready, then run COMMAND against them and stop everything, returning COMMAND's status; without "
      "COMMAND, serve until Ctrl-C. COMMAND sees PIDLAB_LCM_URL, PIDLAB_CHANNEL_PREFIX and "
      "PIDLAB_{PLANT,CONTROLLER,DISTURBANCE}_PID.");
  app->add_option("--lcm-url", o.lcm_url,
                  "LCM URL (default: udpm://239.255.76.67:7667?ttl=0 with a 4 MB receive buffer)");
  app->add_option("--channel-prefix", o.channel_prefix, "channel prefix of this trio")->capture_default_str();
  app->add_option("--log", o.log_file, "record every message with lcm-logger into this file (overwritten)");
  app->add_flag("--isolated", flags->isolated,
                "run everything in a private network namespace (root) with multicast over its "
                "loopback: nothing leaves the machine");
  app->add_option("--drop-rate", o.drop_rate,
                  "fault injection in each process: fraction of received messages thrown away")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--ready-timeout", o.ready_timeout_s, "seconds to wait for the trio to be ready")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option(
      "--auth-key", o.auth_key_file,
      "authenticate every message with the key in this file (HMAC-SHA256, docs/security.md); passed "
      "to the processes and to COMMAND as $PIDLAB_AUTH_KEY_FILE");
  app->add_flag("--verbose,-v", o.verbose, "verbose processes and launcher");
  app->add_option("command", flags->command, "COMMAND [ARGS...] after --");
  return [flags] {
    std::string error;
    if (!flags->options.IsValid(&error)) throw BadInput(error);
    // An unwritable --log is bad input (exit 2), found before anything starts.
    CheckOutputFile(flags->options.log_file, "--log");
    if (flags->isolated && !launcher::EnterIsolatedNetwork(&error)) throw std::runtime_error(error);
    struct sigaction sa {};
    sa.sa_handler = OnSignal;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);

    std::unique_ptr<launcher::Launcher> launched;
    try {
      launched = std::make_unique<launcher::Launcher>(flags->options, Note);
    } catch (const std::invalid_argument& bad) {
      throw BadInput(bad.what());
    }
    launcher::Launcher& trio = *launched;
    if (trio.Start(&g_signal, &error) != launcher::LaunchStatus::kReady) {
      if (g_signal) return 128 + static_cast<int>(g_signal);
      throw std::runtime_error(error);
    }
    const launcher::LaunchOptions& opt = flags->options;
    std::cerr << "pidlab launch: trio ready on " << trio.lcm_url() << " prefix " << opt.channel_prefix
              << (opt.log_file.empty() ? "" : ", logging to " + opt.log_file) << "\n";
    int result = trio.Run(flags->command, &g_signal);
    if (!trio.FinishLog(g_signal != 0) && result == 0) result = 1;
    trio.Stop();
    return result;
  };
}

}  // namespace pidlab::cli
