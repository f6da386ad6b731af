// The phase of L continuous in w (loop_analysis.h, LoopPhaseDeg): the rational
// part followed along the frequencies, the pure delay's phase added exactly.
// Unwrapping arg L itself on a grid aliases once e^{-jwL} turns by more than
// half a turn between neighbours, which a log grid does at every frequency
// well above 1/L.

#include <cmath>
#include <string>
#include <vector>

#include "pidlab/analysis/loop_analysis.h"

namespace pidlab::analysis {
namespace {

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
// A step of the rational part's phase beyond this is bisected: a continuous
// turn of up to 180 degrees between two points cannot be told from its
// opposite, one of 45 can.
constexpr double kResolvedStepDeg = 45.0;
constexpr int kMaxBisections = 12;
// The low-frequency asymptote is looked for this far below the first point.
constexpr int kDecadesBelow = 6;
constexpr int kPointsPerDecadeBelow = 20;

// arg of L's rational part, degrees in (-180, 180]; NaN where L is not finite.
double RationalDeg(const LoopFrequencyPoint& p) {
  if (!std::isfinite(p.l.real()) || !std::isfinite(p.l.imag())) return std::nan("");
  return std::arg(p.l * std::polar(1.0, -p.delay_phase_rad)) * kDegPerRad;
}

// x + 360 k nearest to `near`.
double Nearest(double x, double near) { return x - 360.0 * std::round((x - near) / 360.0); }

class RationalPhase {
 public:
  RationalPhase(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options)
      : plant_(plant), gains_(gains), options_(options) {}

  // The rational phase at w, unwrapped next to `near` (the phase at w_near)
  // by bisecting [w_near, w] in log w while a step exceeds kResolvedStepDeg.
  Status Follow(double w_near, double near, double w, int depth, double* phase) const {
    LoopFrequencyPoint p;
    if (const Status st = At(w, &p); !st.ok()) return st;
    const double x = RationalDeg(p);
    if (!std::isfinite(x) || !std::isfinite(near)) {
      *phase = x;
      return Status::Ok();
    }
    *phase = Nearest(x, near);
    if (std::abs(*phase - near) <= kResolvedStepDeg || depth >= kMaxBisections) return Status::Ok();
    const double mid = std::sqrt(w_near * w);
    double at_mid = 0.0;
    if (const Status st = Follow(w_near, near, mid, depth + 1, &at_mid); !st.ok()) return st;
    return Follow(mid, at_mid, w, depth + 1, phase);
  }

  Status At(double w, LoopFrequencyPoint* p) const {
    std::vector<LoopFrequencyPoint> one;
    if (const Status st = Response({w}, &one); !st.ok()) return st;
    *p = one.front();
    return Status::Ok();
  }

  Status Response(const std::vector<double>& w, std::vector<LoopFrequencyPoint>* out) const {
    return LoopFrequencyResponse(plant_, gains_, options_, w, out);
  }

 private:
  const Plant& plant_;
  const PidGains& gains_;
  const evaluation::LoopOptions& options_;
};

// The rational phase at the first point, on the branch of the asymptote
// c (jw)^-k far below it: -90 k, or -90 k - 180 for c < 0, in (-315, 45].
Status FirstBranch(const RationalPhase& rational, double w0, double principal, double* phase) {
  const int n = kDecadesBelow * kPointsPerDecadeBelow;
  std::vector<double> w;
  for (int i = n; i > 0; --i)
    w.push_back(w0 * std::pow(10.0, -static_cast<double>(i) / kPointsPerDecadeBelow));
  std::vector<LoopFrequencyPoint> below;
  if (const Status st = rational.Response(w, &below); !st.ok()) return st;
  double at = RationalDeg(below.front());
  if (!std::isfinite(at)) {
    *phase = principal;
    return Status::Ok();
  }
  const double asymptote = 90.0 * std::round(at / 90.0);
  at += Nearest(asymptote, -135.0) - asymptote;
  double w_at = w.front();
  for (std::size_t i = 1; i <= below.size(); ++i) {
    const double next = i == below.size() ? principal : RationalDeg(below[i]);
    const double w_next = i == below.size() ? w0 : w[i];
    if (!std::isfinite(next)) continue;
    const double step = Nearest(next, at) - at;
    if (std::abs(step) <= kResolvedStepDeg)
      at += step;
    else if (const Status st = rational.Follow(w_at, at, w_next, 0, &at); !st.ok())
      return st;
    w_at = w_next;
  }
  *phase = Nearest(principal, at);
  return Status::Ok();
}

}  // namespace

Status LoopPhaseDeg(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                    const std::vector<LoopFrequencyPoint>& response, std::vector<double>* phase_deg) {
  phase_deg->clear();
  for (std::size_t i = 1; i < response.size(); ++i)
    if (!(response[i].w_rad_s > response[i - 1].w_rad_s))
      return Status::InvalidInput("LoopPhaseDeg: frequency " + std::to_string(response[i].w_rad_s) +
                                  " rad/s does not increase on " + std::to_string(response[i - 1].w_rad_s));
  const RationalPhase rational(plant, gains, options);
  double last = std::nan(""), w_last = 0.0;
  for (const LoopFrequencyPoint& p : response) {
    const double principal = RationalDeg(p);
    double phase = principal;
    if (!std::isfinite(principal)) {
      phase_deg->push_back(principal);
      continue;
    }
    if (std::isfinite(last)) {
      phase = Nearest(principal, last);
      if (std::abs(phase - last) > kResolvedStepDeg)
        if (const Status st = rational.Follow(w_last, last, p.w_rad_s, 0, &phase); !st.ok()) return st;
    } else if (const Status st = FirstBranch(rational, p.w_rad_s, principal, &phase); !st.ok()) {
      return st;
    }
    // Follow evaluates the same frequency again: its principal value is this one's.
    phase = Nearest(principal, phase);
    last = phase;
    w_last = p.w_rad_s;
    phase_deg->push_back(phase + p.delay_phase_rad * kDegPerRad);
  }
  return Status::Ok();
}

}  // namespace pidlab::analysis
