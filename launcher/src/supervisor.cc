#include "pidlab/launcher/supervisor.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace pidlab::launcher {
namespace {

std::vector<char*> Argv(std::vector<std::string>* args) {
  std::vector<char*> v;
  for (auto& a : *args) v.push_back(a.data());
  v.push_back(nullptr);
  return v;
}

}  // namespace

std::string DescribeStatus(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("killed by signal ") + strsignal(WTERMSIG(status));
  if (WIFSTOPPED(status)) return std::string("stopped by signal ") + strsignal(WSTOPSIG(status));
  return "stopped";
}

int ExitCodeOf(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 1;
}

Status RunAndWait(const std::vector<std::string>& args) {
  std::vector<std::string> copy = args;
  const pid_t pid = fork();
  if (pid < 0) {
    return Status::RunnerFailed("fork failed");
  }
  if (pid == 0) {
    auto argv = Argv(&copy);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return Status::Ok();
  std::string line;
  for (const auto& a : args) line += (line.empty() ? "" : " ") + a;
  return Status::RunnerFailed("'" + line + "' " + DescribeStatus(status));
}

Supervisor::~Supervisor() { KillAll(); }

pid_t Supervisor::Start(const std::string& name, const std::vector<std::string>& args,
                        const std::map<std::string, std::string>& env, int nice,
                        const std::string& stderr_path) {
  std::vector<std::string> copy = args;
  // A group whose every process has ended cannot be joined (setpgid fails and
  // the child would stay in ours, out of KillAll's reach): start a new one.
  if (pgid_ > 0 && kill(-pgid_, 0) != 0 && errno == ESRCH) pgid_ = -1;
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    setpgid(0, pgid_ > 0 ? pgid_ : 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(1);  // the supervisor died before prctl
    for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
    if (nice != 0) setpriority(PRIO_PROCESS, 0, nice);
    if (!stderr_path.empty()) {
      const int fd = open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
      if (fd >= 0) dup2(fd, STDERR_FILENO);
    } else if (!stderr_path_.empty()) {
      const int fd = open(stderr_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
      if (fd >= 0) dup2(fd, STDERR_FILENO);
    }
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    auto argv = Argv(&copy);
    execvp(argv[0], argv.data());
    const std::string line = "pidlab launch: cannot run " + args[0] + ": " + strerror(errno) + "\n";
    if (::write(STDERR_FILENO, line.data(), line.size()) < 0) _exit(127);
    _exit(127);
  }
  // Also in the parent, so the group exists whichever runs first.
  setpgid(pid, pgid_ > 0 ? pgid_ : pid);
  if (pgid_ <= 0) pgid_ = pid;
  children_.push_back({name, pid, true, 0});
  return pid;
}

std::vector<Child> Supervisor::Reap() {
  std::vector<Child> ended;
  for (Child& c : children_) {
    if (!c.alive) continue;
    int status = 0;
    if (waitpid(c.pid, &status, WNOHANG | WUNTRACED) != c.pid) continue;
    if (WIFSTOPPED(status)) {
      Child stopped = c;
      stopped.status = status;
      stopped_.push_back(stopped);
      continue;
    }
    c.alive = false;
    c.status = status;
    ended.push_back(c);
  }
  return ended;
}

std::vector<Child> Supervisor::TakeStopped() {
  std::vector<Child> stopped;
  stopped.swap(stopped_);
  return stopped;
}

Child* Supervisor::FindMutable(pid_t pid) {
  for (Child& c : children_)
    if (c.pid == pid) return &c;
  return nullptr;
}

const Child* Supervisor::Find(pid_t pid) const {
  for (const Child& c : children_)
    if (c.pid == pid) return &c;
  return nullptr;
}

bool Supervisor::StopChild(pid_t pid, int sig, double timeout_s) {
  Child* c = FindMutable(pid);
  if (!c || !c->alive) return true;
  kill(pid, sig);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      c->alive = false;
      c->status = status;
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

void Supervisor::KillAll() {
  for (Child& c : children_)
    if (c.alive && !StopChild(c.pid, SIGTERM, 1.0)) StopChild(c.pid, SIGKILL, 1.0);
  if (pgid_ > 0) killpg(pgid_, SIGKILL);  // anything a child started
  for (Child& c : children_)
    if (c.alive) waitpid(c.pid, &c.status, 0), c.alive = false;
}

}  // namespace pidlab::launcher
