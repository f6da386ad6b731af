#include "pidlab/launcher/launcher.h"

#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <pidlab/lcmt_ready.hpp>
#include <sstream>
#include <stdexcept>

#include "pidlab/transport/episode_start.h"
#include "pidlab/transport/pacing.h"

namespace pidlab::launcher {
namespace {
constexpr const char* kRecvBufSuffix = "&recv_buf_size=4194304";
// Below this much free space beside the log, launch says so before it starts,
// rather than only when a logger fails.
constexpr long long kLowSpaceBytes = 64LL << 20;

bool Started(const std::vector<std::string>& roles, const std::string& role) {
  return std::find(roles.begin(), roles.end(), role) != roles.end();
}
}  // namespace

const std::vector<std::string>& AllRoles() {
  static const std::vector<std::string> roles = {"plant", "controller", "disturbance"};
  return roles;
}

Status EnterIsolatedNetwork() {
  if (unshare(CLONE_NEWNET) != 0)
    return Status::RunnerFailed(std::string("cannot enter a private network namespace (unshare: ") +
                                strerror(errno) + "; root is needed)");
  for (const std::vector<std::string>& args : {std::vector<std::string>{"ip", "link", "set", "lo", "up"},
                                               {"ip", "link", "set", "lo", "multicast", "on"},
                                               {"ip", "route", "add", "224.0.0.0/4", "dev", "lo"}}) {
    if (Status st = RunAndWait(args); !st.ok()) return st;
  }
  return Status::Ok();
}

std::string SelfDirectory() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
  const std::string exe(buf, static_cast<std::size_t>(n));
  return exe.substr(0, exe.rfind('/') + 1);
}

bool LaunchOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  std::string role_error;  // the first role named that is not one, or twice
  for (const std::string& role : roles) {
    if (!Started(AllRoles(), role))
      role_error = "'" + role.substr(0, 120) + "' is not a role (plant, controller, disturbance)";
    else if (std::count(roles.begin(), roles.end(), role) > 1)
      role_error = "'" + role + "' is named twice";
    if (!role_error.empty()) break;
  }
  if (roles.empty())
    os << "--roles names no role: name at least one of plant, controller, disturbance";
  else if (!role_error.empty())
    os << "--roles: " << role_error;
  else if (!(drop_rate >= 0.0 && drop_rate < 1.0))
    os << "--drop-rate " << drop_rate << " must be in [0, 1)";
  else if (!(ready_timeout_s > 0.0))
    os << "--ready-timeout " << ready_timeout_s << " must be positive";
  else if (realtime_factor != 0.0 && !transport::RealtimeFactorIsValid(realtime_factor, error))
    return false;
  else if (rt_priority != kRtPriorityDefault && (rt_priority < 0 || rt_priority > 99))
    os << "--rt-priority " << rt_priority << " must be in 0..99 (0: normal scheduling)";
  else {
    transport::TransportOptions t;
    t.channel_prefix = channel_prefix;
    return t.IsValid(error);
  }
  if (error) *error = os.str();
  return false;
}

int LaunchOptions::EffectiveRtPriority() const {
  if (rt_priority != kRtPriorityDefault) return rt_priority;
  return realtime_factor > 0.0 ? kRealtimeRtPriority : 0;
}

bool RealtimePriorityAllowed(int priority, std::string* why) {
  const int policy = sched_getscheduler(0);
  sched_param before{};
  sched_getparam(0, &before);
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
    const int err = errno;
    if (why)
      *why = std::string(std::strerror(err)) + "; needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO of " +
             std::to_string(priority) + " or more";
    return false;
  }
  sched_setscheduler(0, policy, &before);  // lowering one's own policy is always allowed
  return true;
}

std::string LaunchOptions::EffectiveLcmUrl() const {
  return lcm_url.empty() ? std::string(transport::kDefaultLcmUrl) + kRecvBufSuffix : lcm_url;
}

Launcher::Launcher(const LaunchOptions& options, NoteFn note)
    : options_(options), note_(std::move(note)), url_(options.EffectiveLcmUrl()) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument(error);
  if (!options_.auth_key_file.empty()) {
    // The processes are started from other directories' points of view too.
    char* real = realpath(options_.auth_key_file.c_str(), nullptr);
    if (real) {
      options_.auth_key_file = real;
      std::free(real);
    }
  }
  if (options_.bin_dir.empty()) options_.bin_dir = SelfDirectory();
  if (options_.bin_dir.back() != '/') options_.bin_dir += '/';
  lcm_ = std::make_unique<lcm::LCM>(url_);
  if (!lcm_->good()) {
    lcm_failure_ = "cannot start LCM on '" + url_ +
                   "': no multicast route? Add one with 'sudo ip route add 224.0.0.0/4 dev lo' or use "
                   "--isolated (see docs/trio.md)";
    return;
  }
  transport::TransportOptions topt;
  topt.channel_prefix = options_.channel_prefix;
  if (!options_.auth_key_file.empty()) {
    transport::AuthKey key;
    if (const Status st = transport::LoadAuthKey(options_.auth_key_file, &key); !st.ok())
      throw std::invalid_argument(st.message());
    topt.auth_key = key;
  }
  try {
    transport_ = std::make_unique<transport::Transport>(lcm_.get(), topt);
  } catch (const std::runtime_error& e) {  // the step lanes' LCM
    lcm_failure_ = e.what();
    return;
  }
  transport_->Subscribe<pidlab::lcmt_ready>(transport::kReadyChannel, [this](const pidlab::lcmt_ready& m) {
    if (m.state == pidlab::lcmt_ready::ALIVE) alive_[m.role] = m.pid;
  });
  supervisor_ = std::make_unique<Supervisor>();
  supervisor_->RedirectStderr(options_.stderr_path);
  if (!options_.log_file.empty()) {
    LogCaptureOptions lopt;
    lopt.log_file = options_.log_file;
    lopt.channel_prefix = options_.channel_prefix;
    lopt.auth_key = topt.auth_key;
    log_ = std::make_unique<LogCapture>(lopt, transport_.get(), supervisor_.get());
  }
}

Launcher::~Launcher() { Stop(); }

void Launcher::Note(const std::string& line) const {
  if (note_) note_(line);
}

pid_t Launcher::pid_of(const std::string& role) const {
  const auto it = roles_.find(role);
  return it == roles_.end() ? -1 : it->second;
}

void Launcher::StartRoles() {
  int seed = 0;
  for (const std::string& role : AllRoles()) {
    ++seed;  // each role's own drop seed (1, 2, 3), wherever the others run
    if (!Started(options_.roles, role)) continue;
    const std::string program = role == "controller" && !options_.controller_program.empty()
                                    ? options_.controller_program
                                    : "pidlab-" + role;
    std::vector<std::string> args = {options_.bin_dir + program, "--lcm-url", url_, "--channel-prefix",
                                     options_.channel_prefix};
    if (role == "controller")
      args.insert(args.end(), options_.controller_args.begin(), options_.controller_args.end());
    if (options_.drop_rate > 0.0) {
      std::ostringstream rate;
      rate.precision(17);
      rate << options_.drop_rate;
      args.insert(args.end(), {"--drop-rate", rate.str(), "--drop-seed", std::to_string(seed)});
    }
    if (options_.verbose) args.push_back("--verbose");
    if (role == "plant" && options_.realtime_factor > 0.0) {
      std::ostringstream factor;
      factor << std::setprecision(17) << options_.realtime_factor;
      args.insert(args.end(), {"--realtime", factor.str()});
    }
    if (options_.EffectiveRtPriority() > 0)  // the whole lockstep loop: a paced plant waits for the others
      args.insert(args.end(), {"--rt-priority", std::to_string(options_.EffectiveRtPriority())});
    if (!options_.auth_key_file.empty()) args.insert(args.end(), {"--auth-key", options_.auth_key_file});
    roles_[role] = supervisor_->Start(program, args);
    if (options_.verbose) Note("started " + program + " (pid " + std::to_string(roles_[role]) + ")");
  }
}

LaunchStatus Launcher::WaitReady(const volatile std::sig_atomic_t* stop, std::string* error) {
  // Ready: every process answers PING with ALIVE carrying its pid.
  const double start = transport::NowSeconds();
  double last_ping = -1;
  for (;;) {
    bool all = true;
    for (const auto& [role, pid] : roles_) all = all && alive_.count(role) && alive_[role] == pid;
    if (all) return LaunchStatus::kReady;
    for (const Child& c : supervisor_->Reap()) {
      *error = c.name + " " + DescribeStatus(c.status) + " before it was ready";
      return LaunchStatus::kChildDied;
    }
    if (stop && *stop) return LaunchStatus::kInterrupted;
    if (transport::NowSeconds() - start > options_.ready_timeout_s) {
      std::ostringstream os;
      os << "not ready within " << options_.ready_timeout_s << " s:";
      for (const auto& [role, pid] : roles_)
        if (!alive_.count(role)) os << " pidlab-" << role;
      os << " (LCM " << url_ << ": multicast route? see docs/trio.md)";
      *error = os.str();
      return LaunchStatus::kNotReady;
    }
    if (transport::NowSeconds() - last_ping > 0.1) {
      pidlab::lcmt_ready ping = transport::MakeReady(pidlab::lcmt_ready::PING, "launch");
      transport_->Publish(transport::kReadyChannel, &ping);
      last_ping = transport::NowSeconds();
    }
    transport_->WaitAndHandle(0.02);
  }
}

LaunchStatus Launcher::Start(const volatile std::sig_atomic_t* stop, std::string* error) {
  if (!lcm_failure_.empty()) {
    if (error) *error = lcm_failure_;
    return LaunchStatus::kLcmFailed;
  }
  if (log_) {
    const long long free_bytes = FreeBytesBeside(options_.log_file);
    if (free_bytes >= 0 && free_bytes < kLowSpaceBytes)
      Note("only " + std::to_string(free_bytes / 1024) + " KiB free beside " + options_.log_file +
           ": the log stops, and the run with it, when the disk is full");
    logger_ = log_->StartLogger(url_);
    log_->StartLaneLoggers(url_);
    if (options_.verbose) Note("started lcm-logger (pid " + std::to_string(logger_) + ")");
  }
  StartRoles();
  const LaunchStatus status = WaitReady(stop, error);
  if (status != LaunchStatus::kReady) {
    supervisor_->KillAll();
    return status;
  }
  if (log_ && !log_->WaitForMarker("start")) {
    supervisor_->KillAll();
    *error = "lcm-logger did not record anything into " + options_.log_file;
    return LaunchStatus::kLoggerSilent;
  }
  return LaunchStatus::kReady;
}

std::map<std::string, std::string> Launcher::CommandEnvironment() const {
  std::map<std::string, std::string> env = {{"PIDLAB_LCM_URL", url_},
                                            {"PIDLAB_CHANNEL_PREFIX", options_.channel_prefix}};
  for (const auto& [role, pid] : roles_) {
    std::string upper = role;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    env["PIDLAB_" + upper + "_PID"] = std::to_string(pid);
  }
  if (logger_ > 0) env["PIDLAB_LOGGER_PID"] = std::to_string(logger_);
  if (!options_.auth_key_file.empty()) env[transport::kAuthKeyFileEnv] = options_.auth_key_file;
  // Let COMMAND find pidlab and the trio binaries next to us.
  const char* path = std::getenv("PATH");
  env["PATH"] = options_.bin_dir + ":" + (path ? path : "/usr/bin:/bin");
  return env;
}

int Launcher::Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop) {
  return Run(command, stop, CommandEnvironment());
}

int Launcher::Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop,
                  const std::map<std::string, std::string>& environment) {
  return RunWatching({this}, command, stop, environment);
}

namespace {
/// "kept FILE and its .lane1, .lane2" (files beside the log named by their
/// suffix, to keep the failure line short); empty if none is left.
std::string KeptFiles(const std::string& log_file, const std::vector<std::string>& files) {
  std::string text;
  const bool log_kept = !files.empty() && files.front() == log_file;
  std::string suffixes;
  for (std::size_t i = log_kept ? 1 : 0; i < files.size(); ++i) {
    const std::string& file = files[i];
    const bool beside =
        log_kept && file.size() > log_file.size() && file.compare(0, log_file.size(), log_file) == 0;
    if (beside)
      suffixes += (suffixes.empty() ? "" : ", ") + file.substr(log_file.size());
    else
      text += (text.empty() ? "" : ", ") + file;
  }
  if (log_kept)
    text = log_file + (suffixes.empty() ? "" : " and its " + suffixes) + (text.empty() ? "" : ", " + text);
  return text.empty() ? "" : "kept " + text;
}
}  // namespace

bool Launcher::Watch(pid_t command, bool serving, bool* command_ended, int* command_status) {
  bool must_stop = false;
  for (const Child& c : supervisor_->Reap()) {
    if (c.pid == command) {
      *command_ended = true;
      *command_status = c.status;
    } else if (log_ && log_->IsLogger(c.pid)) {
      // Without its logger the run records nothing more: stop it now, not
      // after COMMAND ran to its end for nothing.
      if (!logger_died_) {
        logger_died_ = true;
        logger_end_ = log_->DescribeLoggerEnd(c) + "; run stopped";
        kept_ = KeptFiles(options_.log_file, log_->AbandonLanes());
        // Stop() adds what the log misses, once the base logger has stopped.
        failure_ = logger_end_ + (kept_.empty() ? "" : "; " + kept_);
      }
      must_stop = true;
    } else {
      Note(c.name + " (pid " + std::to_string(c.pid) + ") " + DescribeStatus(c.status));
      must_stop = must_stop || serving;  // serving: a dead process ends the trio
    }
  }
  // A stopped process answers nothing until continued: said once, as it happens.
  for (const Child& c : supervisor_->TakeStopped())
    if (c.pid != command) Note(c.name + " (pid " + std::to_string(c.pid) + ") " + DescribeStatus(c.status));
  return must_stop;
}

int Launcher::RunWatching(const std::vector<Launcher*>& trios, const std::vector<std::string>& command,
                          const volatile std::sig_atomic_t* stop,
                          const std::map<std::string, std::string>& environment) {
  Launcher& first = *trios.front();
  Supervisor& supervisor = *first.supervisor_;
  const pid_t cmd = command.empty() ? -1 : supervisor.Start("COMMAND", command, environment);
  for (;;) {
    bool command_ended = false, must_stop = false;
    int command_status = 0;
    for (Launcher* trio : trios)
      must_stop =
          trio->Watch(trio == &first ? cmd : -1, cmd < 0, &command_ended, &command_status) || must_stop;
    if (command_ended) return ExitCodeOf(command_status);
    if (must_stop) {
      // COMMAND is told with SIGTERM and has 1 s to finish.
      if (cmd > 0 && !supervisor.StopChild(cmd, SIGTERM, 1.0)) supervisor.StopChild(cmd, SIGKILL, 1.0);
      return 1;
    }
    if (stop && *stop) {
      if (cmd < 0) return 0;  // Ctrl-C is how a serving launch ends
      // Ctrl-C reaches COMMAND as SIGINT; it gets 2 s to finish.
      if (!supervisor.StopChild(cmd, SIGINT, 2.0)) supervisor.StopChild(cmd, SIGKILL, 1.0);
      const Child* c = supervisor.Find(cmd);
      return c && !c->alive ? ExitCodeOf(c->status) : 128 + static_cast<int>(*stop);
    }
    first.transport_->WaitAndHandle(0.02);
    // Every trio's launcher hears its own trio's episodes (EpisodeWitness):
    // what the others queued meanwhile is handled now.
    for (Launcher* trio : trios)
      for (int i = 0; trio != &first && i < 256 && trio->transport_->WaitAndHandle(0.0) > 0; ++i) {
      }
  }
}

bool Launcher::FinishLog(bool interrupted) {
  if (!log_) return true;
  if (logger_died_) return false;  // failure() says why
  if (!log_->WaitForMarker("end")) {
    failure_ = "could not confirm that " + options_.log_file +
               " is complete: lcm-logger did not record the end marker (check it with pidlab replay)";
    return false;
  }
  if (interrupted) {
    Note("interrupted: " + options_.log_file +
         " was not checked for completeness (check it with pidlab replay)");
    return true;
  }
  const RepairSummary summary = log_->Repair();
  const bool ok = summary.status == RepairStatus::kComplete || summary.status == RepairStatus::kRepaired;
  for (const std::string& line : summary.notes) Note("note: " + line);
  if (ok) {
    for (const std::string& line : summary.lines) Note(line);
    return true;
  }
  // One line says why; the other problems are counted (and noted with -v).
  failure_ = summary.lines.empty() ? options_.log_file + " could not be checked" : summary.lines.front();
  if (summary.lines.size() > 1)
    failure_ += " (and " + std::to_string(summary.lines.size() - 1) + " more, -v)";
  if (options_.verbose)
    for (std::size_t i = 1; i < summary.lines.size(); ++i) Note(summary.lines[i]);
  return false;
}

void Launcher::Stop() {
  if (!supervisor_) return;
  if (logger_ > 0) supervisor_->StopChild(logger_, SIGINT, 3.0);
  if (logger_died_) {
    // The lane files were kept as they are (failure() names them). What the
    // log misses is read now, after COMMAND was stopped, not before.
    failure_ = logger_end_ + "; " + log_->DescribeMissing() + (kept_.empty() ? "" : "; " + kept_);
  } else if (const Status merged = log_ ? log_->MergeLanes() : Status::Ok(); !merged.ok()) {
    if (failure_.empty())
      failure_ = merged.message() + " (" + options_.log_file + " holds the base port's events only)";
  } else if (log_ && log_->rebuilt_outputs() > 0)
    Note("note: lcm-logger lost " + std::to_string(log_->rebuilt_outputs()) +
         " PLANT_OUTPUT datagrams on the step lane; written into " + options_.log_file +
         " from the trajectory chunks");
  supervisor_->KillAll();
}

std::string TrioUrl(const std::string& base_url, int index) {
  if (index == 0) return base_url;
  // The step lanes' port arithmetic: trio i's port is the base port + 3 i.
  return transport::StepLaneUrl(base_url, 3 * index);
}

TrioSet::TrioSet(const LaunchOptions& options, int trios, Launcher::NoteFn note) {
  if (trios < 1 || trios > kMaxTrios)
    throw std::invalid_argument("--trios " + std::to_string(trios) + " must be in [1, " +
                                std::to_string(kMaxTrios) + "]");
  const std::string base = options.EffectiveLcmUrl();
  for (int i = 0; i < trios; ++i) {
    LaunchOptions o = options;
    o.lcm_url = TrioUrl(base, i);
    if (o.lcm_url.empty() || transport::StepLaneUrl(o.lcm_url, transport::kControlLane).empty())
      throw std::invalid_argument("--trios " + std::to_string(trios) + " needs ports up to 3 x " +
                                  std::to_string(trios) + " above the port of '" + base +
                                  "' (a udpm:// URL with a port at most " +
                                  std::to_string(65533 - 3 * (trios - 1)) + ")");
    if (i > 0 && !o.log_file.empty()) o.log_file += ".trio" + std::to_string(i + 1);
    Launcher::NoteFn trio_note = note;
    if (trios > 1 && note)
      trio_note = [note, i](const std::string& line) { note("trio " + std::to_string(i + 1) + ": " + line); };
    trios_.push_back(std::make_unique<Launcher>(o, trio_note));
  }
}

LaunchStatus TrioSet::Start(const volatile std::sig_atomic_t* stop, std::string* error) {
  for (std::size_t i = 0; i < trios_.size(); ++i) {
    const LaunchStatus status = trios_[i]->Start(stop, error);
    if (status != LaunchStatus::kReady) {
      if (trios_.size() > 1 && error) *error = "trio " + std::to_string(i + 1) + ": " + *error;
      return status;
    }
  }
  return LaunchStatus::kReady;
}

std::vector<std::string> TrioSet::urls() const {
  std::vector<std::string> urls;
  for (const auto& trio : trios_) urls.push_back(trio->lcm_url());
  return urls;
}

std::map<std::string, std::string> TrioSet::CommandEnvironment() const {
  std::map<std::string, std::string> env = trios_.front()->CommandEnvironment();
  env["PIDLAB_TRIOS"] = std::to_string(trios_.size());
  std::string list;
  for (const std::string& url : urls()) list += (list.empty() ? "" : " ") + url;
  env["PIDLAB_LCM_URLS"] = list;
  for (std::size_t i = 0; i < trios_.size(); ++i) {
    for (const std::string& role : AllRoles()) {
      const pid_t pid = trios_[i]->pid_of(role);
      if (pid <= 0) continue;
      std::string upper = role;
      for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      env["PIDLAB_TRIO" + std::to_string(i + 1) + "_" + upper + "_PID"] = std::to_string(pid);
    }
  }
  return env;
}

int TrioSet::Run(const std::vector<std::string>& command, const volatile std::sig_atomic_t* stop) {
  std::vector<Launcher*> trios;
  for (const auto& trio : trios_) trios.push_back(trio.get());
  return Launcher::RunWatching(trios, command, stop, CommandEnvironment());
}

std::string TrioSet::failure() const {
  for (std::size_t i = 0; i < trios_.size(); ++i)
    if (!trios_[i]->failure().empty())
      return (trios_.size() > 1 ? "trio " + std::to_string(i + 1) + ": " : "") + trios_[i]->failure();
  return "";
}

bool TrioSet::FinishLog(bool interrupted) {
  bool ok = true;
  for (const auto& trio : trios_) ok = trio->FinishLog(interrupted) && ok;
  return ok;
}

void TrioSet::Stop() {
  for (const auto& trio : trios_) trio->Stop();
}

}  // namespace pidlab::launcher
