#include "pidlab/plant_sim/disturbance.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

namespace pidlab {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// SplitMix64: a counter-based generator, so noise sample k is a pure function
// of (seed, k) and needs no state.
std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double UnitUniform(std::uint64_t bits) {  // (0, 1]
  return (static_cast<double>(bits >> 11) + 1.0) * (1.0 / 9007199254740992.0);
}

double StandardNormal(std::uint64_t seed, std::int64_t k) {
  const std::uint64_t base = SplitMix64(seed ^ SplitMix64(static_cast<std::uint64_t>(k)));
  const double u1 = UnitUniform(SplitMix64(base));
  const double u2 = UnitUniform(SplitMix64(base + 1));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

constexpr double kBreakTolerance = 1e-9;

}  // namespace

bool ParseDisturbanceKind(const std::string& s, DisturbanceKind* kind) {
  if (s == "none")
    *kind = DisturbanceKind::kNone;
  else if (s == "square")
    *kind = DisturbanceKind::kSquare;
  else if (s == "step")
    *kind = DisturbanceKind::kStep;
  else if (s == "sine")
    *kind = DisturbanceKind::kSine;
  else if (s == "noise")
    *kind = DisturbanceKind::kNoise;
  else if (s == "prbs")
    *kind = DisturbanceKind::kPrbs;
  else if (s == "chirp")
    *kind = DisturbanceKind::kChirp;
  else
    return false;
  return true;
}

std::string ToString(DisturbanceKind kind) {
  switch (kind) {
    case DisturbanceKind::kNone:
      return "none";
    case DisturbanceKind::kSquare:
      return "square";
    case DisturbanceKind::kStep:
      return "step";
    case DisturbanceKind::kSine:
      return "sine";
    case DisturbanceKind::kNoise:
      return "noise";
    case DisturbanceKind::kPrbs:
      return "prbs";
    case DisturbanceKind::kChirp:
      return "chirp";
  }
  return "none";
}

bool DisturbanceOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  const std::pair<const char*, double> fields[] = {
      {"disturbance amplitude ", amplitude}, {"disturbance period ", period_s},
      {"disturbance phase ", phase_s},       {"disturbance step time ", step_time_s},
      {"noise hold ", noise_hold_s},         {"chirp band f0 ", chirp_f0_hz},
      {"chirp band f1 ", chirp_f1_hz},       {"chirp duration ", chirp_duration_s}};
  for (const auto& [name, v] : fields) {
    if (std::isfinite(v) && std::abs(v) > kMaxDisturbanceMagnitude) {
      os << name << v << " must be at most " << kMaxDisturbanceMagnitude << " in magnitude";
      if (error) *error = os.str();
      return false;
    }
  }
  if (!std::isfinite(amplitude))
    os << "disturbance amplitude " << amplitude << " must be finite";
  else if (kind == DisturbanceKind::kNoise && amplitude < 0.0)
    os << "noise amplitude (standard deviation) " << amplitude << " must be >= 0";
  else if ((kind == DisturbanceKind::kSquare || kind == DisturbanceKind::kSine) &&
           !(period_s > 0.0 && std::isfinite(period_s)))
    os << "disturbance period " << period_s << " s must be positive and finite";
  else if (!std::isfinite(phase_s))
    os << "disturbance phase " << phase_s << " s must be finite";
  else if (kind == DisturbanceKind::kStep && !(step_time_s >= 0.0 && std::isfinite(step_time_s)))
    os << "disturbance step time " << step_time_s << " s must be >= 0 and finite";
  else if ((kind == DisturbanceKind::kNoise || kind == DisturbanceKind::kPrbs) &&
           !(noise_hold_s > 0.0 && std::isfinite(noise_hold_s)))
    os << (kind == DisturbanceKind::kPrbs ? "prbs clock (noise hold) " : "noise hold ") << noise_hold_s
       << " s must be positive";
  else if (!std::isfinite(chirp_f0_hz) || !std::isfinite(chirp_f1_hz) || !std::isfinite(chirp_duration_s))
    os << "chirp band " << chirp_f0_hz << "," << chirp_f1_hz << " Hz and duration " << chirp_duration_s
       << " s must be finite";
  else if (kind == DisturbanceKind::kChirp && !(chirp_f0_hz >= 0.0 && chirp_f0_hz < chirp_f1_hz))
    os << "chirp band " << chirp_f0_hz << "," << chirp_f1_hz << " Hz must have 0 <= F0 < F1";
  else if (kind == DisturbanceKind::kChirp && !(chirp_duration_s > 0.0))
    os << "chirp duration " << chirp_duration_s << " s must be positive";
  else
    return true;
  if (error) *error = os.str();
  return false;
}

Disturbance::Disturbance(const DisturbanceOptions& options) : options_(options) {}

double Disturbance::PieceIndex(double t, double piece) { return std::floor(t / piece + kBreakTolerance); }

double Disturbance::Value(double t) const {
  const DisturbanceOptions& o = options_;
  if (t < -kBreakTolerance) return 0.0;
  switch (o.kind) {
    case DisturbanceKind::kNone:
      return 0.0;
    case DisturbanceKind::kSquare: {
      const double k = PieceIndex(t + o.phase_s, o.period_s / 2.0);
      return std::fmod(std::abs(k), 2.0) == 0.0 ? o.amplitude : -o.amplitude;
    }
    case DisturbanceKind::kStep:
      return t + kBreakTolerance >= o.step_time_s ? o.amplitude : 0.0;
    case DisturbanceKind::kSine:
      return o.amplitude * std::sin(kTwoPi * (t + o.phase_s) / o.period_s);
    case DisturbanceKind::kNoise:
      return o.amplitude * StandardNormal(o.seed, static_cast<std::int64_t>(PieceIndex(t, o.noise_hold_s)));
    case DisturbanceKind::kPrbs: {
      const double k = std::fmod(PieceIndex(t, o.noise_hold_s), static_cast<double>(kPrbsLength));
      const auto start = static_cast<std::int64_t>(o.seed % static_cast<std::uint64_t>(kPrbsLength));
      return PrbsBit((static_cast<std::int64_t>(k) + start) % kPrbsLength) ? o.amplitude : -o.amplitude;
    }
    case DisturbanceKind::kChirp: {
      if (t < 0.0 || t > o.chirp_duration_s) return 0.0;
      // The phase in cycles from t alone (never accumulated).
      const double cycles =
          o.chirp_f0_hz * t + (o.chirp_f1_hz - o.chirp_f0_hz) * t * t / (2.0 * o.chirp_duration_s);
      return o.amplitude * std::sin(kTwoPi * cycles);
    }
  }
  return 0.0;
}

bool Disturbance::IsPiecewiseConstant() const {
  return options_.kind != DisturbanceKind::kSine && options_.kind != DisturbanceKind::kChirp;
}

double Disturbance::NextBreakpoint(double t) const {
  const DisturbanceOptions& o = options_;
  const double inf = std::numeric_limits<double>::infinity();
  switch (o.kind) {
    case DisturbanceKind::kNone:
    case DisturbanceKind::kSine:
    case DisturbanceKind::kChirp:
      return inf;
    case DisturbanceKind::kStep:
      return (o.step_time_s > t + kBreakTolerance) ? o.step_time_s : inf;
    case DisturbanceKind::kSquare: {
      const double half = o.period_s / 2.0;
      return (PieceIndex(t + o.phase_s, half) + 1.0) * half - o.phase_s;
    }
    case DisturbanceKind::kNoise:
    case DisturbanceKind::kPrbs:
      return (PieceIndex(t, o.noise_hold_s) + 1.0) * o.noise_hold_s;
  }
  return inf;
}

bool MeasurementNoise::IsValid(std::string* error) const {
  const bool noise_ok = sigma >= 0.0 && sigma <= kMaxDisturbanceMagnitude;
  if (noise_ok && resolution >= 0.0 && resolution <= kMaxDisturbanceMagnitude) return true;
  std::ostringstream os;
  if (noise_ok)
    os << "measurement resolution " << resolution << " must be >= 0, finite and at most "
       << kMaxDisturbanceMagnitude;
  else
    os << "measurement noise " << sigma << " must be >= 0, finite and at most " << kMaxDisturbanceMagnitude;
  if (error) *error = os.str();
  return false;
}

double MeasurementNoise::Value(std::int64_t k) const {
  if (sigma == 0.0) return 0.0;
  return sigma * StandardNormal(SplitMix64(seed ^ kMeasurementNoiseStream), k);
}

bool PrbsBit(std::int64_t i) {
  // Fibonacci register: the output is bit 0; the feedback bit 0 ^ bit 1
  // (taps 15 and 14) enters at bit 14.
  static const std::vector<bool> sequence = [] {
    std::vector<bool> bits(static_cast<std::size_t>(kPrbsLength));
    std::uint32_t state = 1;
    for (auto&& bit : bits) {
      bit = (state & 1u) != 0;
      const std::uint32_t feedback = (state ^ (state >> 1)) & 1u;
      state = (state >> 1) | (feedback << (kPrbsOrder - 1));
    }
    return bits;
  }();
  return sequence[static_cast<std::size_t>(i)];
}

}  // namespace pidlab
