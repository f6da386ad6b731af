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

int RoleMain(int argc, char** argv, const std::string& program, const std::string& description,
             const RoleFactory& factory, RealtimeFlags* realtime) {
  CLI::App app{description, program};
  std::string url = kDefaultLcmUrl;
  TransportOptions transport_options;
  bool verbose = false;
  app.add_option("--lcm-url", url, "LCM URL (add ?recv_buf_size=N for bursts)")->capture_default_str();
  app.add_option("--channel-prefix", transport_options.channel_prefix, "prefix of every channel")
      ->capture_default_str();
  app.add_option("--drop-rate", transport_options.drop_rate,
                 "fault injection: fraction in [0, 1) of received messages to throw away")
      ->capture_default_str();
  app.add_option("--drop-seed", transport_options.drop_seed, "seed of the fault injection")
      ->capture_default_str();
  std::string auth_key_file;
  app.add_option("--auth-key", auth_key_file,
                 "authenticate every message with the key in this file (HMAC-SHA256; docs/security.md); "
                 "default $PIDLAB_AUTH_KEY_FILE");
  app.add_flag("--verbose,-v", verbose, "log every resend and episode start, not only one line per episode");
  CLI::Option* realtime_option = nullptr;
  if (realtime) {
    realtime_option =
        app.add_option(
               "--realtime", realtime->factor,
               "pace every episode: step k starts no earlier than t0 + k dt / FACTOR on CLOCK_MONOTONIC "
               "(FACTOR 1 without a value: wall-clock period dt); the SUMMARY reports missed deadlines, "
               "lateness and the rate achieved (docs/trio.md)")
            ->expected(0, 1)
            ->default_str("1");
  }
  // Every role takes --rt-priority: in lockstep a paced plant waits for the
  // controller and the disturbance, so all three need the same policy.
  int rt_priority = 0;
  app.add_option("--rt-priority", rt_priority,
                 "ask for SCHED_FIFO at this priority (1-99) and lock the process's memory; if the system "
                 "refuses, say so and continue");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 2;
  }
  std::string error;
  if (auth_key_file.empty()) {
    const char* env = std::getenv(kAuthKeyFileEnv);
    if (env && *env) auth_key_file = env;
  }
  if (!auth_key_file.empty()) {
    AuthKey key;
    if (!LoadAuthKey(auth_key_file, &key, &error)) {
      std::cerr << program << ": error: " << error << "\n";
      return 2;
    }
    transport_options.auth_key = key;
  }
  if (realtime_option && realtime_option->count() > 0 && !RealtimeFactorIsValid(realtime->factor, &error)) {
    std::cerr << program << ": error: " << error << "\n";
    return 2;
  }
  if (rt_priority < 0 || rt_priority > 99) {
    std::cerr << program << ": error: --rt-priority " << rt_priority << " must be in 1..99\n";
    return 2;
  }
  if (realtime) realtime->rt_priority = rt_priority;
  if (rt_priority > 0) {
    // Before LCM starts its receive thread, which inherits the policy.
    sched_param param{};
    param.sched_priority = rt_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
      const int err = errno;
      std::cerr << program << ": note: --rt-priority " << rt_priority << ": SCHED_FIFO refused ("
                << std::strerror(err) << "; needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO); running at normal "
                << "priority\n";
    } else {
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
  }
  transport_options.step_lane_base_url = url;
  if (!transport_options.IsValid(&error)) {
    std::cerr << program << ": error: " << error << "\n";
    return 2;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << program << ": failed: cannot start LCM on '" << url
              << "' (no multicast route? see docs/trio.md, or run under pidlab launch --isolated)\n";
    return 1;
  }
  // The resend timer is a few hundred microseconds (rtt.h): without this, a
  // non-real-time thread's waits end up to 50 us late (the default timer slack).
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  Transport transport(&lcm, transport_options);
  LogFn log = [&program](const std::string& line) {
    const std::string text = program + ": " + line + "\n";
    // One write per line, so the lines of three processes never interleave.
    if (::write(STDERR_FILENO, text.data(), text.size()) < 0) return;
  };
  std::unique_ptr<Role> role = factory(&transport, log, verbose);
  if (verbose) log("serving on " + url + " with prefix " + transport_options.channel_prefix);
  const int status = ServeRole(&transport, role.get(), &g_stop);
  if (status != 0) std::cerr << program << ": failed: LCM receive error\n";
  if (verbose) {
    const TransportCounters& c = transport.counters();
    log("received " + std::to_string(c.received) + ", dropped " + std::to_string(c.dropped) +
        ", undecodable " + std::to_string(c.undecodable) + ", unauthenticated " +
        std::to_string(c.unauthenticated) + ", replayed " + std::to_string(c.replayed) + ", foreign " +
        std::to_string(role->counters().foreign) + ", conflicts " +
        std::to_string(role->counters().conflicts));
  }
  return status;
}

}  // namespace pidlab::transport
