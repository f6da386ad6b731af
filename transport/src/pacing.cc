#include "pidlab/transport/pacing.h"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace pidlab::transport {
namespace {

int64_t MonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

/// Nearest rank: the smallest value with at least q of the values at or below it.
double Percentile(std::vector<double>* values, double q) {
  if (values->empty()) return 0.0;
  const auto n = values->size();
  auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  rank = std::clamp<std::size_t>(rank, 1, n);
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(rank - 1), values->end());
  return (*values)[rank - 1];
}

}  // namespace

bool RealtimeFactorIsValid(double factor, std::string* error) {
  if (factor > 0.0 && std::isfinite(factor)) return true;
  if (error) {
    std::ostringstream os;
    os << "--realtime " << factor << " must be a positive, finite factor (1: wall-clock period dt)";
    *error = os.str();
  }
  return false;
}

std::string DescribeRealtime(const RealtimeStats& s) {
  if (!s.paced()) return "";
  std::ostringstream os;
  auto us = [](double v) { return std::to_string(std::lround(v * 1e6)) + " us"; };
  os << "paced " << s.factor << "x: " << s.missed_deadlines << " missed deadline"
     << (s.missed_deadlines == 1 ? "" : "s") << ", lateness p50 " << us(s.lateness_p50_s) << ", p99 "
     << us(s.lateness_p99_s) << ", max " << us(s.lateness_max_s) << ", " << std::fixed << std::setprecision(1)
     << s.rate_hz << " steps/s";
  return os.str();
}

RealtimeStats CombineRealtime(const RealtimeStats& a, const RealtimeStats& b) {
  if (!a.paced()) return b;
  if (!b.paced()) return a;
  RealtimeStats c = a;
  c.steps = a.steps + b.steps;
  c.missed_deadlines = a.missed_deadlines + b.missed_deadlines;
  c.lateness_p50_s = std::max(a.lateness_p50_s, b.lateness_p50_s);
  c.lateness_p99_s = std::max(a.lateness_p99_s, b.lateness_p99_s);
  c.lateness_max_s = std::max(a.lateness_max_s, b.lateness_max_s);
  c.rate_hz = std::min(a.rate_hz, b.rate_hz);
  return c;
}

RealtimeStats RealtimeFromSummary(const pidlab::lcmt_episode_summary& m) {
  RealtimeStats s;
  if (!(m.realtime_factor > 0.0) || !std::isfinite(m.realtime_factor)) return s;
  s.factor = m.realtime_factor;
  s.steps = static_cast<long>(m.step);
  s.missed_deadlines = static_cast<long>(m.missed_deadlines);
  s.lateness_p50_s = m.lateness_p50_s;
  s.lateness_p99_s = m.lateness_p99_s;
  s.lateness_max_s = m.lateness_max_s;
  s.rate_hz = m.rate_hz;
  return s;
}

void SetRealtime(const RealtimeStats& s, pidlab::lcmt_episode_summary* m) {
  m->realtime_factor = s.factor;
  m->missed_deadlines = s.missed_deadlines;
  m->lateness_p50_s = s.lateness_p50_s;
  m->lateness_p99_s = s.lateness_p99_s;
  m->lateness_max_s = s.lateness_max_s;
  m->rate_hz = s.rate_hz;
}

int LatenessBin(double lateness_s) {
  const double us = lateness_s * 1e6;
  if (!(us >= 1.0)) return 0;          // below 1 us (and NaN)
  const int bin = std::ilogb(us) + 1;  // [2^(i-1), 2^i) us
  return std::min(bin, kLatenessBins - 1);
}

double LatenessBinUpperEdge(int bin) {
  if (bin >= kLatenessBins - 1) return std::numeric_limits<double>::infinity();
  return std::ldexp(1e-6, std::max(bin, 0));
}

double PacingProgress::UpperPercentile(double q) const {
  if (steps <= 0) return 0.0;
  const auto rank = std::clamp<long>(static_cast<long>(std::ceil(q * static_cast<double>(steps))), 1, steps);
  long seen = 0;
  for (int bin = 0; bin < kLatenessBins; ++bin) {
    seen += histogram[static_cast<std::size_t>(bin)];
    if (seen >= rank) return std::min(LatenessBinUpperEdge(bin), lateness_max_s);
  }
  return lateness_max_s;
}

void SetPacingProgress(const PacingProgress& p, pidlab::lcmt_pacing_progress* m) {
  m->step = p.steps;
  m->realtime_factor = p.factor;
  m->period_s = p.period_s;
  m->missed_deadlines = p.missed_deadlines;
  m->lateness_max_s = p.lateness_max_s;
  m->rate_hz = p.rate_hz;
  for (int bin = 0; bin < kLatenessBins; ++bin)
    m->lateness_histogram[bin] = p.histogram[static_cast<std::size_t>(bin)];
  m->lateness_p50_upper_s = p.UpperPercentile(0.50);
  m->lateness_p99_upper_s = p.UpperPercentile(0.99);
}

PacingProgress PacingProgressFromMessage(const pidlab::lcmt_pacing_progress& m) {
  PacingProgress p;
  p.factor = m.realtime_factor;
  p.period_s = m.period_s;
  p.steps = static_cast<long>(m.step);
  p.missed_deadlines = static_cast<long>(m.missed_deadlines);
  p.lateness_max_s = m.lateness_max_s;
  p.rate_hz = m.rate_hz;
  for (int bin = 0; bin < kLatenessBins; ++bin)
    p.histogram[static_cast<std::size_t>(bin)] = static_cast<long>(m.lateness_histogram[bin]);
  return p;
}

Pacer::Pacer(double factor, double dt_s, long total_steps) : factor_(factor), period_s_(dt_s / factor) {
  lateness_s_.reserve(static_cast<std::size_t>(std::max(0L, total_steps)));
}

void Pacer::Start() {
  t0_ns_ = last_start_ns_ = MonotonicNs();
  last_step_ = 0;
  lateness_s_.clear();
  progress_ = PacingProgress{};
  progress_.factor = factor_;
  progress_.period_s = period_s_;
}

void Pacer::WaitForStep(long k) {
  const int64_t due_ns =
      t0_ns_ + static_cast<int64_t>(std::llround(static_cast<double>(k) * period_s_ * 1e9));
  timespec due{static_cast<time_t>(due_ns / 1000000000LL), static_cast<long>(due_ns % 1000000000LL)};
  // Absolute: a signal or a late wake-up never shifts the schedule. Not
  // earlier than due: returns at once if step k is already late.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &due, nullptr) == EINTR) {
  }
  const int64_t now_ns = MonotonicNs();
  const double lateness_s = static_cast<double>(now_ns - due_ns) * 1e-9;
  lateness_s_.push_back(lateness_s);
  last_start_ns_ = now_ns;
  last_step_ = k;
  ++progress_.steps;
  if (lateness_s > period_s_) ++progress_.missed_deadlines;
  progress_.lateness_max_s = std::max(progress_.lateness_max_s, lateness_s);
  ++progress_.histogram[static_cast<std::size_t>(LatenessBin(lateness_s))];
}

PacingProgress Pacer::Progress() const {
  PacingProgress p = progress_;
  const double span = static_cast<double>(last_start_ns_ - t0_ns_) * 1e-9;
  p.rate_hz = span > 0.0 ? static_cast<double>(last_step_) / span : 0.0;
  return p;
}

RealtimeStats Pacer::Stats() const {
  RealtimeStats s;
  s.factor = factor_;
  s.steps = static_cast<long>(lateness_s_.size());
  if (lateness_s_.empty()) return s;
  std::vector<double> v = lateness_s_;
  for (double l : v)
    if (l > period_s_) ++s.missed_deadlines;
  s.lateness_max_s = *std::max_element(v.begin(), v.end());
  s.lateness_p99_s = Percentile(&v, 0.99);
  s.lateness_p50_s = Percentile(&v, 0.50);
  const double span = static_cast<double>(last_start_ns_ - t0_ns_) * 1e-9;
  s.rate_hz = span > 0.0 ? static_cast<double>(last_step_) / span : 0.0;
  return s;
}

}  // namespace pidlab::transport
