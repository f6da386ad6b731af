#pragma once
// Starts the trio (pidlab-plant, pidlab-controller, pidlab-disturbance, and
// lcm-logger when a log is asked for), waits until every process answers,
// runs a command against them or serves, and stops everything. The library
// behind `pidlab launch`, and what `pidlab report` uses to run its trio
// episode in process. LaunchOptions::roles starts only some of the three on
// this host (the others run on other hosts on the same LCM URL).

#include <sys/types.h>

#include <csignal>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pidlab/launcher/log_capture.h"
#include "pidlab/launcher/supervisor.h"
#include "pidlab/spec/status.h"
#include "pidlab/transport/transport.h"

namespace pidlab::launcher {

/// Puts this process (and every child it starts later) in a private network
/// namespace with multicast routed over its loopback: nothing it sends leaves
/// the namespace. Needs root (CAP_SYS_ADMIN). Call it before any thread that
/// uses the network starts. A failed Status (kRunnerFailed) if it cannot.
Status EnterIsolatedNetwork();

/// The directory of this executable, with a trailing '/'.
std::string SelfDirectory();

/// The three roles, in the order they are started: "plant", "controller",
/// "disturbance".
const std::vector<std::string>& AllRoles();

struct LaunchOptions {
  /// The roles started on this host: a non-empty subset of AllRoles(), each
  /// named once (any order; they start in AllRoles() order).
  std::vector<std::string> roles = AllRoles();
  /// LCM URL of the trio; empty: transport::kDefaultLcmUrl with a 4 MB
  /// receive buffer.
  std::string lcm_url;
  std::string channel_prefix = transport::kDefaultChannelPrefix;
  /// Where pidlab-plant, pidlab-controller and pidlab-disturbance are; empty:
  /// this executable's directory.
  std::string bin_dir;
  /// Record every message with lcm-logger into this file (empty: no log).
  std::string log_file;
  /// Fault injection in each process: fraction in [0, 1) of received
  /// messages thrown away (seeds 1, 2, 3 for plant, controller, disturbance,
  /// whichever are started).
  double drop_rate = 0.0;
  /// How long the processes have to answer PING, s.
  double ready_timeout_s = 5.0;
  bool verbose = false;
  /// Real-time pacing of the plant (pidlab-plant --realtime FACTOR,
  /// transport/pacing.h): 0 off, else positive and finite.
  double realtime_factor = 0.0;
  /// --rt-priority N for every role (SCHED_FIFO, memory locked): 1..99; 0
  /// none; kRtPriorityDefault: kRealtimeRtPriority when paced, else none.
  static constexpr int kRtPriorityDefault = -1;
  static constexpr int kRealtimeRtPriority = 50;
  int rt_priority = kRtPriorityDefault;
  /// The processes append their stderr to this file (empty: ours).
  std::string stderr_path;
  /// Authenticate every message with the key in this file (empty: no key):
  /// passed to the processes with --auth-key and to COMMAND as
  /// $PIDLAB_AUTH_KEY_FILE; the launcher's own messages carry it too.
  std::string auth_key_file;
  /// The controller role's program in bin_dir (empty: pidlab-controller) and
  /// the arguments it takes after the common ones: pidlab launch --controller
  /// pil:DIR runs pidlab-controller-pil --firmware DIR/pil.elf --core C.
  std::string controller_program;
  std::vector<std::string> controller_args;

  bool IsValid(std::string* error) const;
  std::string EffectiveLcmUrl() const;
  /// The priority the roles are given: rt_priority, or for the default
  /// kRealtimeRtPriority when realtime_factor > 0 and 0 otherwise.
  int EffectiveRtPriority() const;
};

/// Whether this system grants SCHED_FIFO at `priority` to the processes the
/// launcher starts: tried on the calling thread and undone at once. False
/// with the system's reason (one line) in *why.
bool RealtimePriorityAllowed(int priority, std::string* why);

enum class LaunchStatus {
  kReady,         // every process answered (and the logger wrote its first marker)
  kChildDied,     // a process ended before it was ready
  kNotReady,      // not every process answered within ready_timeout_s
  kLoggerSilent,  // lcm-logger did not record anything
  kInterrupted,   // *stop became true
  kLcmFailed,     // LCM did not start on the URL (nothing was started)
};

class Launcher {
 public:
  /// Where the launcher reports (one line each; "pidlab launch: " is not
  /// included). May be empty.
  using NoteFn = std::function<void(const std::string& line)>;

  /// Throws std::invalid_argument for invalid options (a key file that cannot
  /// be read included): a caller's mistake. If LCM cannot start on the URL,
  /// Start returns kLcmFailed with the reason.
  Launcher(const LaunchOptions& options, NoteFn note);
  ~Launcher();

  /// Starts the logger (if any) and the processes of options.roles and waits
  /// until all of them are ready. Anything else than kReady comes with *error (one line).
  LaunchStatus Start(const volatile std::sig_atomic_t* stop, std::string* error);

  /// PIDLAB_LCM_URL, PIDLAB_CHANNEL_PREFIX, PIDLAB_{PLANT,CONTROLLER,
  /// DISTURBANCE}_PID of the roles started here, PIDLAB_LOGGER_PID (with a
  /// log), PIDLAB_AUTH_KEY_FILE (with a key) and PATH with this executable's
  /// directory first.
  std::map<std::string, std::string> CommandEnvironment() const;

  /// Runs `command` with CommandEnvironment() until it ends and returns its
  /// exit code (128 + signal if killed). *stop forwards SIGINT to it (2 s to
  /// finish). With an empty command, serves until *stop (returns 0) or until
  /// a process dies (returns 1). A process of the trio that ends is reaped at
  /// once and noted. An lcm-logger that ends stops the run: COMMAND gets
  /// SIGTERM (1 s, then SIGKILL), Run returns 1 and failure() says why.
  int Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop);
  /// The same with this environment for COMMAND instead of CommandEnvironment().
  int Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop,
          const std::map<std::string, std::string>& environment);

  /// After Run, with a log: confirms that the log is complete (end marker)
  /// and repairs it. Returns false if it is not known complete; failure()
  /// says why (the first problem, the others counted; noted with verbose).
  /// After a logger died: false at once.
  bool FinishLog(bool interrupted);

  /// Stops the logger (SIGINT, so it closes the file) and every process.
  /// After a logger died the lane files are not merged but kept, and the log
  /// is read to name in failure() the episode it misses steps of
  /// (LogCapture::DescribeMissing); a merge that fails sets failure() if
  /// nothing did before.
  void Stop();

  /// Why the run failed, one line: a logger died (which file, how, the cause
  /// it gave, after Stop the episode and steps the log misses, the files
  /// kept), the log is not known complete (FinishLog), or the lanes could not
  /// be merged (Stop). Empty if none of these.
  const std::string& failure() const { return failure_; }

  const std::string& lcm_url() const { return url_; }
  /// The pid of a role started here; -1 for a role not started here.
  pid_t pid_of(const std::string& role) const;

 private:
  friend class TrioSet;
  void Note(const std::string& line) const;
  /// Runs COMMAND (started by trios[0]) while watching every trio's
  /// processes; see Run.
  static int RunWatching(const std::vector<Launcher*>& trios, const std::vector<std::string>& command,
                         const volatile std::sig_atomic_t* stop,
                         const std::map<std::string, std::string>& environment);
  /// Reaps this trio's processes that ended and notes each (COMMAND `command`
  /// excepted: *command_ended, *command_status). True if the run must stop:
  /// a logger ended (failure_ set), or, when `serving`, any process.
  bool Watch(pid_t command, bool serving, bool* command_ended, int* command_status);
  LaunchStatus WaitReady(const volatile std::sig_atomic_t* stop, std::string* error);
  void StartRoles();

  LaunchOptions options_;
  NoteFn note_;
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::string lcm_failure_;  // why LCM did not start (Start returns kLcmFailed)
  std::unique_ptr<transport::Transport> transport_;
  std::unique_ptr<Supervisor> supervisor_;
  std::unique_ptr<LogCapture> log_;
  std::map<std::string, pid_t> roles_;  // "plant" -> pid
  std::map<std::string, int32_t> alive_;
  pid_t logger_ = -1;
  std::string failure_;
  bool logger_died_ = false;
  /// After a logger died: how it ended, and the files kept ("kept ...").
  std::string logger_end_, kept_;
};

/// The LCM URL of trio `index` (0-based) of `pidlab launch --trios K`: the
/// base URL with its port moved up by 3 index (each trio also uses the two
/// ports above its own for its step lanes, transport.h). Empty if the URL is
/// not udpm:// or a port would pass 65535.
std::string TrioUrl(const std::string& base_url, int index);

/// `pidlab launch --trios K`: K independent trios (each a Launcher with the
/// same options on TrioUrl(base, i)), so that K episodes run at the same
/// time without any process receiving another trio's datagrams. With a log,
/// trio 1 logs into the file named and trio i into FILE.trio<i>.
class TrioSet {
 public:
  /// At most this many trios.
  static constexpr int kMaxTrios = 64;
  /// Throws std::invalid_argument for invalid options or a trio count out
  /// of [1, kMaxTrios] or ports past 65535, std::runtime_error if LCM
  /// cannot start.
  TrioSet(const LaunchOptions& options, int trios, Launcher::NoteFn note);

  /// Starts every trio in turn; stops at the first that is not ready.
  LaunchStatus Start(const volatile std::sig_atomic_t* stop, std::string* error);
  /// Trio 1's environment, plus PIDLAB_TRIOS (K), PIDLAB_LCM_URLS (the K
  /// URLs, separated by spaces) and PIDLAB_TRIO<i>_{PLANT,CONTROLLER,
  /// DISTURBANCE}_PID for i = 1..K.
  std::map<std::string, std::string> CommandEnvironment() const;
  /// Runs COMMAND (or serves) as Launcher::Run does, watching every trio: a
  /// process of any trio that ends is reaped at once and noted with its
  /// trio's number ("trio 2: pidlab-plant (pid N) killed by signal Killed"),
  /// one that is stopped is noted too ("... stopped by signal Stopped (signal)");
  /// COMMAND goes on (a tune moves its episodes to the trios still alive). A
  /// logger of any trio that ends stops the run.
  int Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop);
  /// FinishLog of every trio; false if any log is not known complete.
  bool FinishLog(bool interrupted);
  void Stop();
  /// The first trio's failure() ("trio i: " before it with K > 1); empty if none.
  std::string failure() const;

  int size() const { return static_cast<int>(trios_.size()); }
  std::vector<std::string> urls() const;

 private:
  std::vector<std::unique_ptr<Launcher>> trios_;
};

}  // namespace pidlab::launcher
