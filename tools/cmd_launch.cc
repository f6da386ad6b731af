// pidlab launch: flags -> LaunchOptions -> pidlab::launcher::Launcher
// (launcher/launcher.h): start the trio, or the --roles named (and
// lcm-logger), run COMMAND or serve, check and repair the log, stop
// everything.

#include <csignal>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/io/files.h"
#include "pidlab/launcher/launcher.h"
#include "pidlab/transport/pacing.h"

namespace pidlab::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;
void OnSignal(int sig) { g_signal = sig; }

bool g_quiet = false;  // --quiet: no notes, only a failure's one line
void Note(const std::string& line) {
  if (!g_quiet) std::cerr << "pidlab launch: " << line << "\n";
}

/// "a,b,c" -> {"a", "b", "c"}; "" -> {} (no role: invalid); empty names are
/// kept (an invalid role '').
std::vector<std::string> SplitRoles(const std::string& text) {
  std::vector<std::string> roles;
  if (text.empty()) return roles;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t comma = text.find(',', begin);
    roles.push_back(text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin));
    if (comma == std::string::npos) return roles;
    begin = comma + 1;
  }
}

/// "trio" for all three roles, else the names: "plant, controller".
std::string Started(const std::vector<std::string>& roles) {
  if (roles.size() == launcher::AllRoles().size()) return "trio";
  std::string text;
  for (const std::string& role : launcher::AllRoles())
    for (const std::string& r : roles)
      if (r == role) text += (text.empty() ? "" : ", ") + role;
  return text;
}

}  // namespace

namespace {

// The flags of `pidlab launch`.
struct LaunchFlags {
  launcher::LaunchOptions options;
  bool isolated = false;
  std::string roles;
  std::string controller;  // "" | pil:DIR
  int trios = 1;
  std::vector<std::string> command;
};

// The roles' real-time priority, said in one line when --realtime chose it
// or when the system refuses it (then the roles run at normal priority and
// each of them does not say so again).
void ResolveRtPriority(launcher::LaunchOptions* o) {
  const int priority = o->EffectiveRtPriority();
  const bool chosen = o->rt_priority == launcher::LaunchOptions::kRtPriorityDefault;
  o->rt_priority = priority;
  if (priority == 0) return;
  std::string why;
  if (!launcher::RealtimePriorityAllowed(priority, &why)) {
    Note("SCHED_FIFO at priority " + std::to_string(priority) + " refused (" + why +
         "): the roles run at normal priority");
    o->rt_priority = 0;
  } else if (chosen) {
    Note("--realtime: the roles run SCHED_FIFO at priority " + std::to_string(priority) +
         " with their memory locked (the default with --realtime; --rt-priority N chooses, 0 none)");
  }
}

// --controller pil:DIR: the firmware pidlab export --pil built in DIR
// (its pil.json names the image and the core) as the controller role.
void SetPilController(const std::string& text, launcher::LaunchOptions* o) {
  if (text.rfind("pil:", 0) != 0 || text.size() == 4)
    throw BadInput("--controller " + Quote(text) + " is not pil:DIR (a folder of pidlab export --pil)");
  const std::string dir = text.substr(4), path = dir + "/pil.json";
  std::string bytes;
  if (const Status st = io::ReadFile(path, kMaxSpecFileBytes, &bytes); !st.ok())
    throw BadInput("--controller " + Quote(text) + ": " + st.message());
  const nlohmann::json j = nlohmann::json::parse(bytes, nullptr, false);
  if (!j.is_object() || !j.contains("elf") || !j.contains("core") || !j["elf"].is_string() ||
      !j["core"].is_string())
    throw BadInput("--controller " + Quote(text) + ": '" + path +
                   "' is missing or not pidlab export --pil's pil.json");
  o->controller_program = "pidlab-controller-pil";
  o->controller_args = {"--firmware", j["elf"].get<std::string>(), "--core", j["core"].get<std::string>(),
                        "--report",   dir + "/pil_report.json"};
}

// Starts the trios, runs COMMAND against them and stops everything.
int RunLaunch(LaunchFlags* flags, const CLI::Option* roles, const CLI::Option* realtime) {
  std::string error;
  if (realtime->count() > 0 && !transport::RealtimeFactorIsValid(flags->options.realtime_factor, &error))
    throw BadInput(error);
  if (roles->count() > 0) flags->options.roles = SplitRoles(flags->roles);
  if (!flags->controller.empty()) SetPilController(flags->controller, &flags->options);
  if (g_quiet && flags->options.verbose) throw BadInput("--quiet and --verbose contradict each other");
  if (g_quiet) flags->options.stderr_path = "/dev/null";
  if (!flags->options.IsValid(&error)) throw BadInput(error);
  // An unwritable --log is bad input (exit 2), found before anything starts.
  CheckOutputFile(flags->options.log_file, "--log");
  if (flags->isolated) Require(launcher::EnterIsolatedNetwork());
  ResolveRtPriority(&flags->options);
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);

  std::unique_ptr<launcher::TrioSet> launched;
  try {
    launched = std::make_unique<launcher::TrioSet>(flags->options, flags->trios, Note);
  } catch (const std::invalid_argument& bad) {
    throw BadInput(bad.what());
  }
  launcher::TrioSet& trio = *launched;
  if (trio.Start(&g_signal, &error) != launcher::LaunchStatus::kReady) {
    if (g_signal) return 128 + static_cast<int>(g_signal);
    throw std::runtime_error(error);
  }
  const launcher::LaunchOptions& opt = flags->options;
  std::string where;
  for (const std::string& url : trio.urls()) where += (where.empty() ? "" : ", ") + url;
  Note((trio.size() > 1 ? std::to_string(trio.size()) + " x " : "") + Started(opt.roles) + " ready on " +
       where + " prefix " + opt.channel_prefix +
       (opt.log_file.empty() ? "" : ", logging to " + opt.log_file));
  const int result = trio.Run(flags->command, &g_signal);
  const bool logger_died = !trio.failure().empty();  // Run stopped COMMAND
  if (!logger_died) trio.FinishLog(g_signal != 0);
  trio.Stop();
  // Launch's own failure is one line (exit 1). When COMMAND failed by
  // itself, its line is the last one and says why: launch returns its status.
  if (!trio.failure().empty() && (logger_died || result == 0)) throw std::runtime_error(trio.failure());
  return result;
}

}  // namespace

std::function<int()> RegisterLaunch(CLI::App* app) {
  auto flags = std::make_shared<LaunchFlags>();
  launcher::LaunchOptions& o = flags->options;
  app->description(
      "Start pidlab-plant, pidlab-controller and pidlab-disturbance, or only the --roles named (and "
      "lcm-logger with --log), wait until all are ready, then run COMMAND against them and stop "
      "everything, returning COMMAND's status; without COMMAND, serve until Ctrl-C. COMMAND sees "
      "PIDLAB_LCM_URL, PIDLAB_CHANNEL_PREFIX and PIDLAB_{PLANT,CONTROLLER,DISTURBANCE}_PID of the roles "
      "started here; with --trios K also PIDLAB_TRIOS, PIDLAB_LCM_URLS (the K URLs) and "
      "PIDLAB_TRIO<i>_{PLANT,CONTROLLER,DISTURBANCE}_PID.");
  app->add_option(
      "--controller", flags->controller,
      "pil:DIR runs the controller role on an emulated Cortex-M: the firmware pidlab export --pil "
      "built in DIR, under pidlab-controller-pil (docs/pil.md)");
  auto* roles = app->add_option(
      "--roles", flags->roles,
      "the roles to start on this host, comma-separated (default: plant,controller,disturbance); the "
      "others run on other hosts on the same --lcm-url (ttl=1 on a LAN, docs/trio.md)");
  app->add_option(
      "--lcm-url", o.lcm_url,
      "LCM URL (default: udpm://239.255.76.67:7667?ttl=0 with a 4 MB receive buffer, which stays on "
      "this host; roles on several hosts need ttl=1)");
  app->add_option("--channel-prefix", o.channel_prefix, "channel prefix of this trio")->capture_default_str();
  app->add_option("--trios", flags->trios,
                  "start K independent trios, trio i on the --lcm-url port + 3(i-1) (each uses its port and "
                  "the two above); 'pidlab tune --backend lcm' runs its starts on all of them. With --log, "
                  "trio i > 1 logs into FILE.trio<i>")
      ->capture_default_str();
  app->add_option("--log", o.log_file,
                  "record every message with lcm-logger into this file (overwritten); after COMMAND, what "
                  "the logger lost is repaired: steps from the plant, configurations from launch's own copy");
  app->add_flag("--isolated", flags->isolated,
                "run everything in a private network namespace (root) with multicast over its "
                "loopback: nothing leaves the machine");
  app->add_option("--drop-rate", o.drop_rate,
                  "fault injection in each process: fraction of received messages thrown away (drop seeds "
                  "1, 2, 3 for plant, controller, disturbance): an episode run again loses the same messages")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option("--ready-timeout", o.ready_timeout_s, "seconds to wait for the trio to be ready")
      ->check(FiniteNumber())
      ->capture_default_str();
  app->add_option(
      "--auth-key", o.auth_key_file,
      "authenticate every message with the key in this file (HMAC-SHA256, docs/security.md); passed "
      "to the processes and to COMMAND as $PIDLAB_AUTH_KEY_FILE");
  auto* realtime =
      app->add_option(
             "--realtime", o.realtime_factor,
             "pace the plant: step k starts no earlier than t0 + k dt / FACTOR on CLOCK_MONOTONIC (FACTOR "
             "1 without a value: wall-clock period dt); episodes report missed deadlines, lateness and "
             "the rate achieved (docs/trio.md)")
          ->expected(0, 1)
          ->default_str("1");
  app->add_option(
         "--rt-priority", o.rt_priority,
         "run the plant, controller and disturbance SCHED_FIFO at this priority (1-99) with their memory "
         "locked, if the system allows it (said in one line if not); default 50 with --realtime "
         "(docs/trio.md), "
         "else none; 0: normal scheduling")
      ->default_str("50 with --realtime, else 0");
  app->add_flag("--verbose,-v", o.verbose, "verbose processes and launcher");
  app->add_flag("--quiet,-q", g_quiet,
                "no notes from launch and no stderr from the processes: stderr holds only a failure's one "
                "line (and COMMAND's own stderr)");
  app->add_option("command", flags->command, "COMMAND [ARGS...] after --");
  return [flags, roles, realtime] { return RunLaunch(flags.get(), roles, realtime); };
}

}  // namespace pidlab::cli
