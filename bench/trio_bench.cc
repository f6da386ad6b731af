// trio_bench: lockstep steps per second of the LCM trio next to a raw LCM
// publish/handle round trip measured in the same run on the same URL, and
// the CPU each costs: CPU-seconds per step of every process of the trio
// (from /proc/PID/stat of $PIDLAB_{PLANT,CONTROLLER,DISTURBANCE,LOGGER}_PID,
// and this client's own) against the CPU of one raw round trip (this
// process and its echo child).
// Run it against a trio, inside a private network namespace:
//   pidlab launch --isolated -- trio_bench [ROUND_TRIPS] [HORIZON_S]

#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/transport/transport.h"

namespace {

using pidlab::transport::NowSeconds;

struct Ping {
  int64_t seq = 0;
};

/// Echo process: answers every BENCH_PING with BENCH_PONG (raw bytes).
class Echo {
 public:
  explicit Echo(lcm::LCM* lcm) : lcm_(lcm) {}
  void OnPing(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    lcm_->publish("BENCH_PONG", rbuf->data, rbuf->data_size);
  }

 private:
  lcm::LCM* lcm_;
};

class Pong {
 public:
  void OnPong(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (rbuf->data_size == sizeof(int64_t)) last = *static_cast<const int64_t*>(rbuf->data);
  }
  int64_t last = -1;
};

double Seconds(const timeval& t) {
  return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
}

/// User + system CPU seconds of this process.
double SelfCpu() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return Seconds(u.ru_utime) + Seconds(u.ru_stime);
}

/// User + system CPU seconds of another process (/proc/PID/stat), -1 if gone.
double ProcessCpu(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return -1.0;
  std::istringstream rest(line.substr(line.rfind(')') + 2));  // fields from 3 (state) on
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::atof(field.c_str());
    if (i == 15) stime = std::atof(field.c_str());
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

struct RoundTrips {
  double per_second = 0;
  double cpu_per_trip_s = 0;  // this process and the echo
};

RoundTrips MeasureRoundTrips(const std::string& url, long n) {
  const pid_t child = fork();
  if (child == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    lcm::LCM lcm(url);
    Echo echo(&lcm);
    lcm.subscribe("BENCH_PING", &Echo::OnPing, &echo);
    for (;;) lcm.handle();
  }
  lcm::LCM lcm(url);
  Pong pong;
  lcm.subscribe("BENCH_PONG", &Pong::OnPong, &pong);
  // Warm up until the echo answers.
  for (int64_t seq = -1000;; --seq) {
    lcm.publish("BENCH_PING", &seq, sizeof(seq));
    const double sent = NowSeconds();
    while (pong.last != seq && NowSeconds() - sent < 0.05) lcm.handleTimeout(10);
    if (pong.last == seq) break;
  }
  const double t0 = NowSeconds();
  const double self0 = SelfCpu(), echo0 = ProcessCpu(child);
  for (int64_t seq = 0; seq < n; ++seq) {
    lcm.publish("BENCH_PING", &seq, sizeof(seq));
    while (pong.last != seq) {
      if (lcm.handleTimeout(100) <= 0) {  // lost: resend, as the trio does
        lcm.publish("BENCH_PING", &seq, sizeof(seq));
      }
    }
  }
  RoundTrips r;
  r.per_second = static_cast<double>(n) / (NowSeconds() - t0);
  r.cpu_per_trip_s = (SelfCpu() - self0 + ProcessCpu(child) - echo0) / static_cast<double>(n);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const long trips = argc > 1 ? std::atol(argv[1]) : 20000;
  const double horizon = argc > 2 ? std::atof(argv[2]) : 20.0;
  const char* env_url = std::getenv("PIDLAB_LCM_URL");
  const std::string url = env_url ? env_url : pidlab::transport::kDefaultLcmUrl;
  pidlab::episode_client::EpisodeClientOptions co;
  co.lcm_url = url;
  if (const char* p = std::getenv("PIDLAB_CHANNEL_PREFIX")) co.transport.channel_prefix = p;
  if (const char* key_file = std::getenv(pidlab::transport::kAuthKeyFileEnv); key_file && *key_file) {
    pidlab::transport::AuthKey key;
    if (const pidlab::Status st = pidlab::transport::LoadAuthKey(key_file, &key); !st.ok()) {
      std::fprintf(stderr, "trio_bench: %s\n", st.message().c_str());
      return 2;
    }
    co.transport.auth_key = key;
  }

  const RoundTrips raw = MeasureRoundTrips(url, trips);
  // The trio's processes, as pidlab launch exports them.
  std::vector<std::pair<std::string, pid_t>> processes;
  for (const char* role : {"PLANT", "CONTROLLER", "DISTURBANCE", "LOGGER"}) {
    const char* pid = std::getenv((std::string("PIDLAB_") + role + "_PID").c_str());
    if (pid && std::atol(pid) > 0) processes.emplace_back(role, static_cast<pid_t>(std::atol(pid)));
  }
  std::vector<double> cpu0;
  for (const auto& p : processes) cpu0.push_back(ProcessCpu(p.second));
  const double client0 = SelfCpu();

  pidlab::Plant plant;
  (void)pidlab::MakePlant("double_integrator", pidlab::StepperMotorParameters{}, &plant);
  pidlab::evaluation::LoopOptions options;
  options.loop = pidlab::evaluation::LoopKind::kSampled;
  options.horizon_s = horizon;
  pidlab::episode_client::EpisodeClient client(co);
  std::vector<double> y;
  for (int episode = 0; episode < 3; ++episode) {
    if (const pidlab::Status st =
            client.Run(plant, pidlab::PidGains{2.0, 1.0, 1.5}, options, options.disturbance, &y, nullptr);
        !st.ok()) {
      std::fprintf(stderr, "trio_bench: %s\n", st.message().c_str());
      return 1;
    }
  }
  const double client_cpu = SelfCpu() - client0;
  const double steps = client.stats().StepsPerSecond();
  const auto n_steps = static_cast<double>(client.stats().steps);
  std::printf("url                 %s%s\n", url.c_str(), co.transport.auth_key ? " (authenticated)" : "");
  std::printf("raw round trip      %.0f /s  (%ld publish/handle round trips, echo process)\n", raw.per_second,
              trips);
  std::printf("lockstep trio       %.0f steps/s  (%ld steps in %ld episodes)\n", steps, client.stats().steps,
              client.stats().episodes);
  std::printf("ratio               %.2f  (target >= 0.8)\n", steps / raw.per_second);
  double total = client_cpu;
  std::printf("CPU per step        client %.1f us", 1e6 * client_cpu / n_steps);
  for (std::size_t i = 0; i < processes.size(); ++i) {
    const double used = ProcessCpu(processes[i].second) - cpu0[i];
    total += used;
    std::printf(", %s %.1f us", processes[i].first.c_str(), 1e6 * used / n_steps);
  }
  std::printf("\nCPU per step, all   %.1f us  (raw round trip: %.1f us; ratio %.2f, target <= 1)\n",
              1e6 * total / n_steps, 1e6 * raw.cpu_per_trip_s, total / n_steps / raw.cpu_per_trip_s);
  return 0;
}
