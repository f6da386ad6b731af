#pragma once
// Ziegler-Nichols ultimate-gain tuning, computed exactly from the plant:
// Ku is the smallest proportional gain that puts the closed loop on the
// stability boundary (poles +/- j wu), Tu = 2 pi / wu.

#include <string>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/transfer_function.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

enum class ZieglerNicholsRule {
  kClassic,        // Kp = 0.6 Ku, Ti = Tu/2, Td = Tu/8
  kPessen,         // Pessen integral rule: Kp = 0.7 Ku, Ti = 0.4 Tu, Td = 0.15 Tu
  kSomeOvershoot,  // Kp = 0.33 Ku, Ti = Tu/2, Td = Tu/3
  kNoOvershoot,    // Kp = 0.2 Ku, Ti = Tu/2, Td = Tu/3
};
/// classic | pessen | some-overshoot | no-overshoot
bool ParseZieglerNicholsRule(const std::string& s, ZieglerNicholsRule* rule);
std::string ToString(ZieglerNicholsRule rule);

struct ZieglerNicholsResult {
  bool applicable = false;
  double ultimate_gain = 0.0;      // Ku
  double ultimate_period_s = 0.0;  // Tu
  double crossover_rad_s = 0.0;    // wu
  PidGains gains;                  // ki = Kp/Ti, kd = Kp Td
  std::string message;             // why not applicable, or a one-line summary
};

/// kInvalidInput naming the reason (and result->applicable = false) where the method
/// does not apply: e.g. 1/s^2 is marginally stable under every proportional
/// gain, so there is no finite ultimate gain; a plant that never reaches the
/// stability boundary under P control has none either.
Status ZieglerNicholsTune(const TransferFunction& tf, ZieglerNicholsRule rule, ZieglerNicholsResult* result);

}  // namespace pidlab::tune
