// The machine's own wake-up latency: what any paced loop on it can achieve at
// best. A thread at SCHED_FIFO (if allowed), memory locked, sleeps with an
// absolute clock_nanosleep(TIMER_ABSTIME) on CLOCK_MONOTONIC to t0 + k period,
// as the paced plant does (transport/pacing.h), and records how late each
// wake-up is. No LCM, no other process: the baseline for `--realtime`
// figures (docs/trio.md, "Real-time pacing"), like rt-tests' cyclictest.
//   wakeup_bench [PERIOD_S=0.001] [DURATION_S=25] [PRIORITY=50]

#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

bool ParsePositive(const char* text, double* value) {
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(text, &end);
  return errno == 0 && end != text && *end == '\0' && *value > 0.0 && *value < 1e6;
}

timespec At(const timespec& t0, long long offset_ns) {
  const long long ns = static_cast<long long>(t0.tv_nsec) + offset_ns;
  timespec t{};
  t.tv_sec = t0.tv_sec + static_cast<time_t>(ns / 1000000000LL);
  t.tv_nsec = static_cast<long>(ns % 1000000000LL);
  return t;
}

double Seconds(const timespec& a, const timespec& b) {  // a - b
  return static_cast<double>(a.tv_sec - b.tv_sec) + 1e-9 * static_cast<double>(a.tv_nsec - b.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf(
        "usage: wakeup_bench [PERIOD_S=0.001] [DURATION_S=25] [PRIORITY=50]\n"
        "Wake-up lateness of an absolute clock_nanosleep loop at SCHED_FIFO: the machine's floor\n"
        "for pidlab launch --realtime (docs/trio.md).\n");
    return 0;
  }
  double period = 1e-3, duration = 25.0, priority = 50.0;
  const char* names[] = {"PERIOD_S", "DURATION_S", "PRIORITY"};
  double* values[] = {&period, &duration, &priority};
  for (int i = 1; i < argc && i <= 3; ++i) {
    if (!ParsePositive(argv[i], values[i - 1])) {
      std::fprintf(stderr, "wakeup_bench: error: %s '%s' must be a positive number\n", names[i - 1], argv[i]);
      return 2;
    }
  }
  if (argc > 4) {
    std::fprintf(stderr, "wakeup_bench: error: unexpected argument '%s'\n", argv[4]);
    return 2;
  }
  sched_param param{};
  param.sched_priority = std::clamp(static_cast<int>(priority), 1, 99);
  const bool fifo = sched_setscheduler(0, SCHED_FIFO, &param) == 0;
  const bool locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  const auto steps = static_cast<long>(duration / period);
  const auto period_ns = static_cast<long long>(period * 1e9 + 0.5);
  std::vector<double> lateness(static_cast<std::size_t>(steps));
  timespec t0{}, now{};
  clock_gettime(CLOCK_MONOTONIC, &t0);
  for (long k = 1; k <= steps; ++k) {
    const timespec due = At(t0, k * period_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &due, nullptr) == EINTR) {
    }
    clock_gettime(CLOCK_MONOTONIC, &now);
    lateness[static_cast<std::size_t>(k - 1)] = Seconds(now, due);
  }
  const long over_period =
      std::count_if(lateness.begin(), lateness.end(), [&](double l) { return l > period; });
  const long over_200us =
      std::count_if(lateness.begin(), lateness.end(), [](double l) { return l > 200e-6; });
  std::vector<double> sorted = lateness;
  std::sort(sorted.begin(), sorted.end());
  auto rank = [&](double q) {  // nearest rank, as the plant's SUMMARY
    const auto i = static_cast<std::size_t>(std::max(1.0, std::ceil(q * static_cast<double>(steps))));
    return sorted[std::min(i, sorted.size()) - 1];
  };
  std::printf("period %g s, %ld wake-ups, %s, memory %s\n", period, steps,
              fifo ? "SCHED_FIFO" : "normal priority (SCHED_FIFO refused)", locked ? "locked" : "not locked");
  std::printf(
      "lateness p50 %.0f us, p99 %.0f us, max %.0f us; later than 200 us: %ld; later than one period: %ld\n",
      1e6 * rank(0.5), 1e6 * rank(0.99), 1e6 * sorted.back(), over_200us, over_period);
  return 0;
}
