#include "pidlab/transport/role_main.h"

#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "pidlab/transport/pacing.h"

namespace pidlab::transport {
namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

namespace {

// What a role's process is told on its command line.
struct RoleFlags {
  std::string url = kDefaultLcmUrl;
  TransportOptions transport;
  bool verbose = false;
  std::string auth_key_file;
  int rt_priority = 0;
  CLI::Option* realtime_option = nullptr;
};

void RegisterRoleFlags(CLI::App* app, RoleFlags* f, RealtimeFlags* realtime) {
  app->add_option("--lcm-url", f->url, "LCM URL (add ?recv_buf_size=N for bursts)")->capture_default_str();
  app->add_option("--channel-prefix", f->transport.channel_prefix, "prefix of every channel")
      ->capture_default_str();
  app->add_option("--drop-rate", f->transport.drop_rate,
                  "fault injection: fraction in [0, 1) of received messages to throw away")
      ->capture_default_str();
  app->add_option("--drop-seed", f->transport.drop_seed,
                  "seed of the fault injection: each decision hashes the seed with the channel, the "
                  "message's step and its copy number, so an episode run again with the same seed loses "
                  "the same messages")
      ->capture_default_str();
  app->add_option("--auth-key", f->auth_key_file,
                  "authenticate every message with the key in this file (HMAC-SHA256; docs/security.md); "
                  "default $PIDLAB_AUTH_KEY_FILE");
  app->add_flag("--verbose,-v", f->verbose,
                "log every resend and episode start, not only one line per episode");
  if (realtime) {
    f->realtime_option =
        app->add_option(
               "--realtime", realtime->factor,
               "pace every episode: step k starts no earlier than t0 + k dt / FACTOR on CLOCK_MONOTONIC "
               "(FACTOR 1 without a value: wall-clock period dt); the SUMMARY reports missed deadlines, "
               "lateness and the rate achieved (docs/trio.md)")
            ->expected(0, 1)
            ->default_str("1");
  }
  // Every role takes --rt-priority: in lockstep a paced plant waits for the
  // controller and the disturbance, so all three need the same policy.
  app->add_option("--rt-priority", f->rt_priority,
                  "ask for SCHED_FIFO at this priority (1-99) and lock the process's memory; if the system "
                  "refuses, say so and continue");
}

// The key file, the pacing factor and the priority; "" or why not.
std::string CheckRoleFlags(RoleFlags* f, RealtimeFlags* realtime) {
  std::string error;
  if (f->auth_key_file.empty()) {
    const char* env = std::getenv(kAuthKeyFileEnv);
    if (env && *env) f->auth_key_file = env;
  }
  if (!f->auth_key_file.empty()) {
    AuthKey key;
    if (const Status st = LoadAuthKey(f->auth_key_file, &key); !st.ok()) return st.message();
    f->transport.auth_key = key;
  }
  if (f->realtime_option && f->realtime_option->count() > 0 &&
      !RealtimeFactorIsValid(realtime->factor, &error))
    return error;
  if (f->rt_priority < 0 || f->rt_priority > 99)
    return "--rt-priority " + std::to_string(f->rt_priority) + " must be in 1..99";
  if (realtime) realtime->rt_priority = f->rt_priority;
  f->transport.step_lane_base_url = f->url;
  if (!f->transport.IsValid(&error)) return error;
  return "";
}

// SCHED_FIFO at the priority asked for, before LCM starts its receive
// thread (which inherits the policy); if the system refuses, say so once.
void AskForRealtimePriority(const std::string& program, int rt_priority, bool verbose) {
  if (rt_priority <= 0) return;
  sched_param param{};
  param.sched_priority = rt_priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
    const int err = errno;
    std::cerr << program << ": note: --rt-priority " << rt_priority << ": SCHED_FIFO refused ("
              << std::strerror(err) << "; needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO); running at normal "
              << "priority\n";
    return;
  }
  // No page fault in the loop: a real-time process keeps its pages (not
  // under AddressSanitizer, whose shadow reserves terabytes).
#if defined(__SANITIZE_ADDRESS__)
  const bool locked = false;
#else
  const bool locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
#endif
  if (verbose)
    std::cerr << program << ": running SCHED_FIFO at priority " << rt_priority
              << (locked ? ", memory locked" : ", memory not locked (mlockall refused)") << "\n";
}

// LCM, the transport and the role, served until a signal or an error.
int Serve(const std::string& program, const RoleFlags& f, const RoleFactory& factory) {
  lcm::LCM lcm(f.url);
  if (!lcm.good()) {
    std::cerr << program << ": failed: cannot start LCM on '" << f.url
              << "' (no multicast route? see docs/trio.md, or run under pidlab launch --isolated)\n";
    return 1;
  }
  // The resend timer is a few hundred microseconds (rtt.h): without this, a
  // non-real-time thread's waits end up to 50 us late (the default timer slack).
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  Transport transport(&lcm, f.transport);
  LogFn log = [&program](const std::string& line) {
    const std::string text = program + ": " + line + "\n";
    // One write per line, so the lines of three processes never interleave.
    if (::write(STDERR_FILENO, text.data(), text.size()) < 0) return;
  };
  std::unique_ptr<Role> role = factory(&transport, log, f.verbose);
  if (!role) return 1;  // the factory said why
  if (f.verbose) log("serving on " + f.url + " with prefix " + f.transport.channel_prefix);
  const int status = ServeRole(&transport, role.get(), &g_stop);
  if (status == 1) std::cerr << program << ": failed: LCM receive error\n";
  const int exit_status = status == 0 ? 0 : 1;
  if (f.verbose) {
    const TransportCounters& c = transport.counters();
    log("received " + std::to_string(c.received) + ", dropped " + std::to_string(c.dropped) +
        ", undecodable " + std::to_string(c.undecodable) + ", unauthenticated " +
        std::to_string(c.unauthenticated) + ", replayed " + std::to_string(c.replayed) + ", foreign " +
        std::to_string(role->counters().foreign) + ", conflicts " +
        std::to_string(role->counters().conflicts));
  }
  return exit_status;
}

}  // namespace

int RoleMain(int argc, char** argv, const std::string& program, const std::string& description,
             const RoleFactory& factory, RealtimeFlags* realtime,
             const std::function<void(CLI::App*)>& more_flags,
             const std::function<std::string()>& check_flags) {
  CLI::App app{description, program};
  RoleFlags flags;
  RegisterRoleFlags(&app, &flags, realtime);
  if (more_flags) more_flags(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 2;
  }
  std::string error = CheckRoleFlags(&flags, realtime);
  if (error.empty() && check_flags) error = check_flags();
  if (!error.empty()) {
    std::cerr << program << ": error: " << error << "\n";
    return 2;
  }
  AskForRealtimePriority(program, flags.rt_priority, flags.verbose);
  return Serve(program, flags, factory);
}

}  // namespace pidlab::transport
