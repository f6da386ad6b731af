// pidlab launch: starts the process trio (and lcm-logger), waits until all
// are ready, then runs COMMAND against them (or serves until Ctrl-C) and
// stops everything. No orphans: every child is in one process group that is
// killed on every exit path, and each child dies with us (PR_SET_PDEATHSIG).

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <pidlab/lcmt_episode_summary.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <pidlab/lcmt_trajectory_request.hpp>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "cli_common.h"
#include "log_reader.h"
#include "pidlab/lcm/transport.h"

namespace pidlab::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;
void OnSignal(int sig) { g_signal = sig; }

constexpr const char* kIsolatedEnv = "PIDLAB_LAUNCH_ISOLATED";
// lcm-logger runs this much nicer than everyone else (negative: higher
// priority), so a loaded machine starves the trio before it starves the logger.
constexpr int kLoggerNice = -10;
// Its socket asks for this receive buffer (the kernel caps it at net.core.rmem_max).
constexpr const char* kRecvBuf = "recv_buf_size=4194304";
// Log repair after COMMAND: rounds of (read log, request missing steps from
// the plant, wait until the answers are in the log).
constexpr int kRepairRounds = 6;
constexpr long kRepairChunk = 2000;  // steps per TRAJECTORY_REQUEST (the plant's chunk limit)

std::string RangesText(const std::vector<std::pair<long, long>>& ranges, std::size_t max_ranges = 8) {
  std::string s;
  for (std::size_t i = 0; i < ranges.size() && i < max_ranges; ++i) {
    s += (i ? "," : "") + std::to_string(ranges[i].first);
    if (ranges[i].second != ranges[i].first) s += "-" + std::to_string(ranges[i].second);
  }
  if (ranges.size() > max_ranges) s += ",... (" + std::to_string(ranges.size()) + " ranges)";
  return s;
}

/// Union of the missing steps of the three streams, as sorted disjoint ranges.
std::vector<std::pair<long, long>> MissingSteps(const replay::Episode& e) {
  std::vector<std::pair<long, long>> all;
  for (const replay::StreamStats* s : {&e.outputs, &e.commands, &e.disturbances})
    all.insert(all.end(), s->missing.begin(), s->missing.end());
  std::sort(all.begin(), all.end());
  std::vector<std::pair<long, long>> merged;
  for (const auto& r : all) {
    if (!merged.empty() && r.first <= merged.back().second + 1)
      merged.back().second = std::max(merged.back().second, r.second);
    else
      merged.push_back(r);
  }
  return merged;
}

long CountSteps(const std::vector<std::pair<long, long>>& ranges) {
  long n = 0;
  for (const auto& r : ranges) n += r.second - r.first + 1;
  return n;
}

std::string SelfExe() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  buf[n] = '\0';
  return buf;
}

std::vector<std::string> SelfArgs() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> args;
  std::string arg;
  while (std::getline(in, arg, '\0')) args.push_back(arg);
  return args;
}

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> v;
  for (auto& a : args) v.push_back(a.data());
  v.push_back(nullptr);
  return v;
}

/// Runs a short set-up command and waits for it.
void RunChecked(std::vector<std::string> args) {
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    auto argv = Argv(args);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string line;
    for (const auto& a : args) line += (line.empty() ? "" : " ") + a;
    throw std::runtime_error("'" + line + "' failed (are we root inside the namespace?)");
  }
}

std::string FileTail(const std::string& path, std::size_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(in.tellg());
  const std::size_t from = size > max_bytes ? size - max_bytes : 0;
  in.seekg(static_cast<std::streamoff>(from));
  std::string s(size - from, '\0');
  in.read(s.data(), static_cast<std::streamsize>(s.size()));
  return s;
}

long FileSize(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? static_cast<long>(st.st_size) : -1;
}

std::string DescribeStatus(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("killed by signal ") + strsignal(WTERMSIG(status));
  return "stopped";
}

int ExitCodeOf(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 1;
}

class Launcher {
 public:
  struct Child {
    std::string name;
    pid_t pid = -1;
    bool alive = false;
    int status = 0;
  };

  explicit Launcher(bool verbose) : verbose_(verbose) {}
  ~Launcher() { KillAll(); }

  /// nice != 0: the child sets its nice value before exec (so every thread
  /// it creates inherits it); a failure (not root) leaves it at ours.
  pid_t Start(const std::string& name, std::vector<std::string> args,
              const std::map<std::string, std::string>& env, int nice = 0) {
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("fork failed");
    if (pid == 0) {
      setpgid(0, pgid_ > 0 ? pgid_ : 0);
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(1);  // the launcher died before prctl
      for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
      if (nice != 0) setpriority(PRIO_PROCESS, 0, nice);
      sigset_t none;
      sigemptyset(&none);
      sigprocmask(SIG_SETMASK, &none, nullptr);
      auto argv = Argv(args);
      execvp(argv[0], argv.data());
      std::cerr << "pidlab launch: cannot run " << args[0] << ": " << strerror(errno) << "\n";
      _exit(127);
    }
    // Also in the parent, so the group exists whichever runs first.
    setpgid(pid, pgid_ > 0 ? pgid_ : pid);
    if (pgid_ <= 0) pgid_ = pid;
    children_.push_back({name, pid, true, 0});
    if (verbose_) {
      std::cerr << "pidlab launch: started " << name << " (pid " << pid << ")";
      if (nice != 0) std::cerr << " asking for nice " << nice;
      std::cerr << "\n";
    }
    return pid;
  }

  /// Reaps exited children; returns the ones that ended since the last call.
  std::vector<Child> Reap() {
    std::vector<Child> ended;
    for (Child& c : children_) {
      if (!c.alive) continue;
      int status = 0;
      if (waitpid(c.pid, &status, WNOHANG) == c.pid) {
        c.alive = false;
        c.status = status;
        ended.push_back(c);
      }
    }
    return ended;
  }

  Child* Find(pid_t pid) {
    for (Child& c : children_)
      if (c.pid == pid) return &c;
    return nullptr;
  }

  /// Sends sig to one child and waits up to timeout_s for it.
  bool StopChild(pid_t pid, int sig, double timeout_s) {
    Child* c = Find(pid);
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

  void KillAll() {
    for (Child& c : children_)
      if (c.alive && !StopChild(c.pid, SIGTERM, 1.0)) StopChild(c.pid, SIGKILL, 1.0);
    if (pgid_ > 0) killpg(pgid_, SIGKILL);  // anything a child started
    for (Child& c : children_)
      if (c.alive) waitpid(c.pid, &c.status, 0), c.alive = false;
  }

 private:
  bool verbose_;
  pid_t pgid_ = -1;
  std::vector<Child> children_;
};

struct LaunchCommand {
  std::string lcm_url, channel_prefix = lcm_trio::kDefaultChannelPrefix, log_file;
  bool isolated = false, verbose = false;
  double drop_rate = 0.0, ready_timeout_s = 5.0;
  std::vector<std::string> command;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Start pidlab-plant, pidlab-controller and pidlab-disturbance (and lcm-logger with --log), wait "
        "until all "
        "are ready, then run COMMAND against them and stop everything, returning COMMAND's status; without "
        "COMMAND, serve until Ctrl-C. COMMAND sees PIDLAB_LCM_URL, PIDLAB_CHANNEL_PREFIX and "
        "PIDLAB_{PLANT,CONTROLLER,DISTURBANCE}_PID.");
    app->add_option("--lcm-url", lcm_url,
                    "LCM URL (default: udpm://239.255.76.67:7667?ttl=0 with a 4 MB receive buffer)");
    app->add_option("--channel-prefix", channel_prefix, "channel prefix of this trio")->capture_default_str();
    app->add_option("--log", log_file, "record every message with lcm-logger into this file (overwritten)");
    app->add_flag("--isolated", isolated,
                  "run everything in a private network namespace (unshare -n, root) with multicast over its "
                  "loopback: nothing leaves the machine");
    app->add_option("--drop-rate", drop_rate,
                    "fault injection in each process: fraction of received messages "
                    "thrown away")
        ->capture_default_str();
    app->add_option("--ready-timeout", ready_timeout_s, "seconds to wait for the trio to be ready")
        ->capture_default_str();
    app->add_flag("--verbose,-v", verbose, "verbose processes and launcher");
    app->add_option("command", command, "COMMAND [ARGS...] after --");
    return [this] { return Run(); };
  }

  int Run() {
    if (!(drop_rate >= 0.0 && drop_rate < 1.0))
      throw BadInput("--drop-rate " + std::to_string(drop_rate) + " must be in [0, 1)");
    if (!(ready_timeout_s > 0.0)) throw BadInput("--ready-timeout must be positive");
    if (isolated && !std::getenv(kIsolatedEnv)) ReexecIsolated();  // does not return
    if (isolated) {
      RunChecked({"ip", "link", "set", "lo", "up"});
      RunChecked({"ip", "link", "set", "lo", "multicast", "on"});
      RunChecked({"ip", "route", "add", "224.0.0.0/4", "dev", "lo"});
    }
    if (lcm_url.empty()) lcm_url = std::string(lcm_trio::kDefaultLcmUrl) + "&recv_buf_size=4194304";
    struct sigaction sa {};
    sa.sa_handler = OnSignal;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);

    lcm::LCM lcm(lcm_url);
    if (!lcm.good())
      throw std::runtime_error(
          "cannot start LCM on '" + lcm_url +
          "': no multicast route? Add one with 'sudo ip route add 224.0.0.0/4 dev lo' or use "
          "--isolated (see docs/trio.md)");
    lcm_trio::TransportOptions topt;
    topt.channel_prefix = channel_prefix;
    std::string error;
    if (!topt.IsValid(&error)) throw BadInput(error);
    lcm_trio::Transport transport(&lcm, topt);
    std::map<std::string, int32_t> alive;
    std::string marker_seen;
    transport.Subscribe<pidlab::lcmt_ready>(lcm_trio::kReadyChannel, [&](const pidlab::lcmt_ready& m) {
      if (m.state == pidlab::lcmt_ready::ALIVE) alive[m.role] = m.pid;
    });

    Launcher launcher(verbose);
    const std::string dir = SelfExe().substr(0, SelfExe().rfind('/') + 1);
    pid_t logger = -1;
    if (!log_file.empty()) {
      // Higher priority and a large receive buffer: under load, the kernel
      // drops datagrams silently when the logger does not read in time.
      std::string logger_url = lcm_url;
      if (logger_url.find("recv_buf_size=") == std::string::npos)
        logger_url += std::string(logger_url.find('?') == std::string::npos ? "?" : "&") + kRecvBuf;
      logger = launcher.Start(
          "lcm-logger",
          {"lcm-logger", "-q", "-f", "--flush-interval=20", "--lcm-url=" + logger_url, log_file}, {},
          kLoggerNice);
    }
    std::map<std::string, pid_t> trio;
    int seed = 1;
    for (const char* role : {"plant", "controller", "disturbance"}) {
      std::vector<std::string> args = {dir + "pidlab-" + role, "--lcm-url", lcm_url, "--channel-prefix",
                                       channel_prefix};
      if (drop_rate > 0.0) {
        args.insert(args.end(),
                    {"--drop-rate", std::to_string(drop_rate), "--drop-seed", std::to_string(seed++)});
      }
      if (verbose) args.push_back("--verbose");
      trio[role] = launcher.Start(std::string("pidlab-") + role, args, {});
    }

    // Ready: every process answers PING with ALIVE carrying its pid.
    const double start = lcm_trio::NowSeconds();
    double last_ping = -1;
    for (;;) {
      bool all = true;
      for (const auto& [role, pid] : trio) all = all && alive.count(role) && alive[role] == pid;
      if (all) break;
      for (const auto& c : launcher.Reap()) {
        launcher.KillAll();
        throw std::runtime_error(c.name + " " + DescribeStatus(c.status) + " before it was ready");
      }
      if (g_signal) return 128 + g_signal;
      if (lcm_trio::NowSeconds() - start > ready_timeout_s) {
        std::string missing;
        for (const auto& [role, pid] : trio)
          if (!alive.count(role)) missing += " pidlab-" + role;
        launcher.KillAll();
        throw std::runtime_error("not ready within " + std::to_string(ready_timeout_s) + " s:" + missing +
                                 " (LCM " + lcm_url + ": multicast route? see docs/trio.md)");
      }
      if (lcm_trio::NowSeconds() - last_ping > 0.1) {
        pidlab::lcmt_ready ping;
        ping.episode_id = 0;
        ping.step = -1;
        ping.state = pidlab::lcmt_ready::PING;
        ping.role = "launch";
        ping.pid = getpid();
        transport.Publish(lcm_trio::kReadyChannel, &ping);
        last_ping = lcm_trio::NowSeconds();
      }
      transport.WaitAndHandle(0.02);
    }
    if (logger > 0 && !WaitForMarker(&transport, &launcher, "start")) {
      launcher.KillAll();
      throw std::runtime_error("lcm-logger did not record anything into " + log_file);
    }
    std::cerr << "pidlab launch: trio ready on " << lcm_url << " prefix " << channel_prefix
              << (log_file.empty() ? "" : ", logging to " + log_file) << "\n";

    int result = 0;
    pid_t cmd = -1;
    if (!command.empty()) {
      std::map<std::string, std::string> env = {
          {"PIDLAB_LCM_URL", lcm_url},
          {"PIDLAB_CHANNEL_PREFIX", channel_prefix},
          {"PIDLAB_PLANT_PID", std::to_string(trio["plant"])},
          {"PIDLAB_CONTROLLER_PID", std::to_string(trio["controller"])},
          {"PIDLAB_DISTURBANCE_PID", std::to_string(trio["disturbance"])}};
      if (logger > 0) env["PIDLAB_LOGGER_PID"] = std::to_string(logger);
      // Let COMMAND find pidlab and the trio binaries next to us.
      const char* path = std::getenv("PATH");
      env["PATH"] = dir + ":" + (path ? path : "/usr/bin:/bin");
      cmd = launcher.Start("COMMAND", command, env);
    }
    bool forwarded = false;
    for (;;) {
      bool done = false;
      for (const auto& c : launcher.Reap()) {
        if (c.pid == cmd) {
          result = ExitCodeOf(c.status);
          done = true;
        } else {
          std::cerr << "pidlab launch: " << c.name << " (pid " << c.pid << ") " << DescribeStatus(c.status)
                    << "\n";
          if (cmd < 0) {  // serving: a dead process ends the trio
            result = 1;
            done = true;
          }
        }
      }
      if (done) break;
      if (g_signal) {
        if (cmd < 0) {
          result = 0;  // Ctrl-C is how a serving launch ends
          break;
        }
        if (!forwarded) {
          forwarded = true;
          // Ctrl-C reaches COMMAND as SIGINT; it gets 2 s to finish.
          if (!launcher.StopChild(cmd, SIGINT, 2.0)) launcher.StopChild(cmd, SIGKILL, 1.0);
          const Launcher::Child* c = launcher.Find(cmd);
          result = c && !c->alive ? ExitCodeOf(c->status) : 128 + g_signal;
          break;
        }
      }
      transport.WaitAndHandle(0.02);
    }
    if (logger > 0) {
      if (!WaitForMarker(&transport, &launcher, "end")) {
        std::cerr << "pidlab launch: error: could not confirm that " << log_file << " is complete\n";
        if (result == 0) result = 1;
      } else if (g_signal) {
        std::cerr << "pidlab launch: interrupted: " << log_file
                  << " was not checked for completeness (check it with pidlab replay)\n";
      } else if (!RepairLog(&transport, &launcher)) {
        if (result == 0) result = 1;
      }
      launcher.StopChild(logger, SIGINT, 3.0);
    }
    launcher.KillAll();
    return result;
  }

  /// Makes sure the log holds every step of every episode in it: reads it
  /// with the replay reader, asks the plant to republish each missing range
  /// as trajectory chunks (which `pidlab replay` fills steps from), waits
  /// until the answers are in the log (marker), and repeats up to
  /// kRepairRounds times. Episodes the plant ended with a FAILED summary are
  /// left as they are (they cannot be complete; COMMAND reported the error).
  /// Returns false, after one line per incomplete episode, if the log is
  /// still incomplete.
  bool RepairLog(lcm_trio::Transport* transport, Launcher* launcher) {
    // The plant's answers, as launch hears them: (episode, first step) -> count.
    std::map<std::pair<int64_t, int64_t>, int> answers;
    transport->Subscribe<pidlab::lcmt_trajectory_chunk>(lcm_trio::kTrajectoryChannel,
                                                        [&answers](const pidlab::lcmt_trajectory_chunk& c) {
                                                          answers[{c.episode_id, c.step}] = c.count;
                                                        });
    replay::ReadOptions options;
    options.channel_prefix = channel_prefix;
    std::map<int64_t, long> republished;  // episode -> steps asked for (all rounds)
    for (int round = 0;; ++round) {
      replay::LogContents log;
      std::string error;
      if (!replay::ReadLog(log_file, options, &log, &error)) {
        std::cerr << "pidlab launch: error: cannot read " << log_file << " to check it: " << error << "\n";
        return false;
      }
      struct Gap {
        int64_t id;
        std::vector<std::pair<long, long>> ranges;
      };
      std::vector<Gap> gaps;
      for (const replay::Episode& e : log.episodes) {
        if (!e.has_config) {
          // Only its configuration can be missing (steps without it are not
          // episodes the reader can rebuild); the plant cannot resend it.
          std::cerr << "pidlab launch: error: " << log_file << " is incomplete: episode " << e.episode_id
                    << ": " << e.CompletenessNote() << "\n";
          return false;
        }
        if (e.Complete()) continue;
        if (e.has_summary && e.summary_status == pidlab::lcmt_episode_summary::FAILED) continue;
        gaps.push_back({e.episode_id, MissingSteps(e)});
      }
      if (gaps.empty()) {
        if (!republished.empty()) {
          std::cerr << "pidlab launch: lcm-logger lost messages; repaired " << log_file
                    << " from the plant's trajectory chunks:";
          for (const auto& [id, n] : republished) std::cerr << " episode " << id << " (" << n << " steps)";
          std::cerr << " in " << round << " round" << (round == 1 ? "" : "s") << "\n";
        }
        return true;
      }
      if (round == kRepairRounds) {
        for (const Gap& g : gaps) {
          bool answered = true;
          for (const auto& r : g.ranges)
            for (long first = r.first; first <= r.second; first += kRepairChunk)
              answered = answered && answers.count({g.id, first});
          std::cerr << "pidlab launch: error: " << log_file << " is incomplete: episode " << g.id
                    << " misses " << CountSteps(g.ranges) << " steps (" << RangesText(g.ranges) << ") after "
                    << kRepairRounds << " repair rounds: "
                    << (answered ? "lcm-logger lost the plant's trajectory chunks every time"
                                 : "pidlab-plant did not resend them (no longer in its history, or it died)")
                    << "\n";
        }
        return false;
      }
      // Ask for every missing range, paced so that the answers (up to 48 kB
      // each) do not overflow the logger's socket in one burst.
      std::set<std::pair<int64_t, int64_t>> asked;
      for (const Gap& g : gaps) {
        republished[g.id] += CountSteps(g.ranges);
        for (const auto& r : g.ranges) {
          for (long first = r.first; first <= r.second; first += kRepairChunk) {
            pidlab::lcmt_trajectory_request req;
            req.episode_id = g.id;
            req.step = first;
            req.count = static_cast<int32_t>(std::min(kRepairChunk, r.second - first + 1));
            answers.erase({g.id, first});
            asked.insert({g.id, first});
            transport->Publish(lcm_trio::kTrajectoryRequestChannel, &req);
            transport->WaitAndHandle(0.005);
          }
        }
      }
      if (verbose)
        std::cerr << "pidlab launch: repair round " << round + 1 << ": asked the plant for " << asked.size()
                  << " trajectory chunks\n";
      // Wait (bounded) until launch heard every answer; then the marker makes
      // sure whatever the logger received is on disk.
      const double t0 = lcm_trio::NowSeconds();
      for (;;) {
        bool all = true;
        for (const auto& key : asked) all = all && answers.count(key);
        if (all || lcm_trio::NowSeconds() - t0 > 1.0) break;
        transport->WaitAndHandle(0.01);
      }
      if (!WaitForMarker(transport, launcher, "repair" + std::to_string(round))) {
        std::cerr << "pidlab launch: error: lcm-logger stopped writing " << log_file
                  << " during its repair\n";
        return false;
      }
    }
  }

  /// Publishes a MARKER until lcm-logger has written it to the log (so
  /// everything published before it is on disk), then waits until the file
  /// stops growing.
  bool WaitForMarker(lcm_trio::Transport* transport, Launcher* launcher, const std::string& what) {
    std::random_device rd;
    const std::string nonce =
        "pidlab-launch-" + what + "-" + std::to_string(getpid()) + "-" + std::to_string(rd());
    pidlab::lcmt_ready m;
    m.episode_id = 0;
    m.step = -1;
    m.state = pidlab::lcmt_ready::MARKER;
    m.role = "launch";
    m.pid = getpid();
    m.detail = nonce;
    const double start = lcm_trio::NowSeconds();
    double last = -1;
    while (lcm_trio::NowSeconds() - start < 10.0) {
      if (FileTail(log_file, 1 << 16).find(nonce) != std::string::npos) {
        long size = FileSize(log_file);
        for (int i = 0; i < 100; ++i) {  // stable for 50 ms
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
          const long now = FileSize(log_file);
          if (now == size) return true;
          size = now;
        }
        return true;
      }
      if (lcm_trio::NowSeconds() - last > 0.2) {
        transport->Publish(lcm_trio::kReadyChannel, &m);
        last = lcm_trio::NowSeconds();
      }
      transport->WaitAndHandle(0.01);
      (void)launcher;
    }
    return false;
  }

  [[noreturn]] void ReexecIsolated() {
    setenv(kIsolatedEnv, "1", 1);
    std::vector<std::string> args = {"unshare", "-n", "--", SelfExe()};
    const std::vector<std::string> self = SelfArgs();
    args.insert(args.end(), self.begin() + 1, self.end());
    auto argv = Argv(args);
    execvp("unshare", argv.data());
    throw std::runtime_error(std::string("cannot run unshare -n: ") + strerror(errno));
  }
};

LaunchCommand command;
const CommandRegistrar registrar("launch", "start the LCM process trio (plant, controller, disturbance)",
                                 [](CLI::App* sub) { return command.Register(sub); });

}  // namespace
}  // namespace pidlab::cli
