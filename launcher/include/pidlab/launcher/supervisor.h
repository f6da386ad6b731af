#pragma once
// Child processes under supervision: every child is in one process group that
// is killed on every exit path, and each child dies with its supervisor
// (PR_SET_PDEATHSIG), so no orphans survive a crash or a kill.

#include <sys/types.h>

#include <map>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"

namespace pidlab::launcher {

struct Child {
  std::string name;
  pid_t pid = -1;
  bool alive = false;
  int status = 0;  // waitpid status once it ended
};

/// "exited with status N", "killed by signal NAME" or "stopped by signal
/// NAME".
std::string DescribeStatus(int status);
/// The shell's convention: the exit status, or 128 + signal.
int ExitCodeOf(int status);

/// Runs a short command and waits for it. A failed Status (kRunnerFailed) quoting the
/// command line if it could not run or did not exit 0.
Status RunAndWait(const std::vector<std::string>& args);

class Supervisor {
 public:
  Supervisor() = default;
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;
  /// Stops every child (SIGTERM, then SIGKILL) and the whole group.
  ~Supervisor();

  /// Starts `args` (looked up on PATH) with `env` added to ours. nice != 0:
  /// the child sets its nice value before exec (every thread it creates
  /// inherits it); a failure (not root) leaves it at ours. stderr_path: this
  /// child's stderr goes to that file (truncated) instead of the one set by
  /// RedirectStderr. Returns the pid; throws std::runtime_error if fork fails.
  pid_t Start(const std::string& name, const std::vector<std::string>& args,
              const std::map<std::string, std::string>& env = {}, int nice = 0,
              const std::string& stderr_path = "");

  /// Children started from now on append their stderr to this file
  /// (empty: they share ours).
  void RedirectStderr(const std::string& path) { stderr_path_ = path; }

  /// Reaps exited children; returns the ones that ended since the last call.
  /// A child that was stopped (SIGSTOP, SIGTSTP) since is not ended: it is
  /// kept for TakeStopped.
  std::vector<Child> Reap();
  /// The children Reap saw stopped since the last call (still alive; status
  /// is the stop status).
  std::vector<Child> TakeStopped();
  /// The child with this pid, or null.
  const Child* Find(pid_t pid) const;
  /// Sends sig to one child and waits up to timeout_s for it to end. True if
  /// it ended (or was not running).
  bool StopChild(pid_t pid, int sig, double timeout_s);
  /// Stops every child and kills the process group.
  void KillAll();

 private:
  Child* FindMutable(pid_t pid);
  pid_t pgid_ = -1;
  std::string stderr_path_;
  std::vector<Child> children_;
  std::vector<Child> stopped_;
};

}  // namespace pidlab::launcher
