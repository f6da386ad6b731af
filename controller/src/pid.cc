#include "pidlab/controller/pid.h"

namespace pidlab {

bool ParseDerivativeOn(const std::string& s, DerivativeOn* v) {
  if (s == "error")
    *v = DerivativeOn::kError;
  else if (s == "measurement")
    *v = DerivativeOn::kMeasurement;
  else
    return false;
  return true;
}

bool ParseIntegralMethod(const std::string& s, IntegralMethod* v) {
  if (s == "backward-euler")
    *v = IntegralMethod::kBackwardEuler;
  else if (s == "forward-euler")
    *v = IntegralMethod::kForwardEuler;
  else if (s == "trapezoidal")
    *v = IntegralMethod::kTrapezoidal;
  else
    return false;
  return true;
}

bool ParseAntiWindup(const std::string& s, AntiWindup* v) {
  if (s == "none")
    *v = AntiWindup::kNone;
  else if (s == "clamping")
    *v = AntiWindup::kClamping;
  else if (s == "back-calculation")
    *v = AntiWindup::kBackCalculation;
  else
    return false;
  return true;
}

std::string ToString(DerivativeOn v) { return v == DerivativeOn::kError ? "error" : "measurement"; }
std::string ToString(IntegralMethod v) {
  switch (v) {
    case IntegralMethod::kBackwardEuler:
      return "backward-euler";
    case IntegralMethod::kForwardEuler:
      return "forward-euler";
    case IntegralMethod::kTrapezoidal:
      return "trapezoidal";
  }
  return "backward-euler";
}
std::string ToString(AntiWindup v) {
  switch (v) {
    case AntiWindup::kNone:
      return "none";
    case AntiWindup::kClamping:
      return "clamping";
    case AntiWindup::kBackCalculation:
      return "back-calculation";
  }
  return "clamping";
}

PidOptions PidOptionsAt(PidOptions options, double loop_dt_s) {
  options.dt_s = loop_dt_s;
  return options;
}

}  // namespace pidlab
