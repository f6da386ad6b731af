// trio_bench: lockstep steps per second of the LCM trio next to a raw LCM
// publish/handle round trip measured in the same run on the same URL.
// Run it against a trio, inside a private network namespace:
//   pidlab launch --isolated -- trio_bench [ROUND_TRIPS] [HORIZON_S]

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "pidlab/tuner/episode_client.h"
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

double RoundTripsPerSecond(const std::string& url, long n) {
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
  for (int64_t seq = 0; seq < n; ++seq) {
    lcm.publish("BENCH_PING", &seq, sizeof(seq));
    while (pong.last != seq) {
      if (lcm.handleTimeout(100) <= 0) {  // lost: resend, as the trio does
        lcm.publish("BENCH_PING", &seq, sizeof(seq));
      }
    }
  }
  const double rate = static_cast<double>(n) / (NowSeconds() - t0);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  return rate;
}

}  // namespace

int main(int argc, char** argv) {
  const long trips = argc > 1 ? std::atol(argv[1]) : 20000;
  const double horizon = argc > 2 ? std::atof(argv[2]) : 20.0;
  const char* env_url = std::getenv("PIDLAB_LCM_URL");
  const std::string url = env_url ? env_url : pidlab::transport::kDefaultLcmUrl;
  pidlab::EpisodeClientOptions co;
  co.lcm_url = url;
  if (const char* p = std::getenv("PIDLAB_CHANNEL_PREFIX")) co.transport.channel_prefix = p;
  std::string error;
  if (const char* key_file = std::getenv(pidlab::transport::kAuthKeyFileEnv); key_file && *key_file) {
    pidlab::transport::AuthKey key;
    if (!pidlab::transport::LoadAuthKey(key_file, &key, &error)) {
      std::fprintf(stderr, "trio_bench: %s\n", error.c_str());
      return 2;
    }
    co.transport.auth_key = key;
  }

  const double raw = RoundTripsPerSecond(url, trips);

  pidlab::Plant plant;
  pidlab::MakePlant("double_integrator", pidlab::StepperMotorParameters{}, &plant, &error);
  pidlab::LoopOptions options;
  options.loop = pidlab::LoopKind::kSampled;
  options.horizon_s = horizon;
  pidlab::EpisodeClient client(co);
  std::vector<double> y;
  for (int episode = 0; episode < 3; ++episode) {
    if (!client.Run(plant, pidlab::PidGains{2.0, 1.0, 1.5}, options, options.disturbance, &y, nullptr,
                    &error)) {
      std::fprintf(stderr, "trio_bench: %s\n", error.c_str());
      return 1;
    }
  }
  const double steps = client.stats().StepsPerSecond();
  std::printf("url                 %s%s\n", url.c_str(), co.transport.auth_key ? " (authenticated)" : "");
  std::printf("raw round trip      %.0f /s  (%ld publish/handle round trips, echo process)\n", raw, trips);
  std::printf("lockstep trio       %.0f steps/s  (%ld steps in %ld episodes)\n", steps, client.stats().steps,
              client.stats().episodes);
  std::printf("ratio               %.2f  (target >= 0.8)\n", steps / raw);
  return 0;
}
