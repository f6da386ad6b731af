#pragma once
// Internal to the design engine (design.h): the continuous loop's responses
// on a uniform grid, and its frequency response on the design grid.

#include <Eigen/Dense>
#include <complex>
#include <vector>

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/plants.h"

namespace pidlab::tune::design {

/// What enters the loop, each a unit step at t = 0: a load d at the plant
/// input, and the reference r seen by the proportional term (weight b), the
/// integral term and the derivative term (weight c). The loop is linear, so
/// the setpoint response with weights b, c is y_i + b y_p + c y_d.
struct Inputs {
  double load = 0.0, r_p = 0.0, r_i = 0.0, r_d = 0.0;
};

/// One response on the grid t_k = k h: y is the plant's output before its
/// dead time, y(t + L) (the same integrals and peaks), u the controller's.
struct Response {
  std::vector<double> y, u;
  /// The response came to rest (false: it grew or was still moving at the
  /// longest horizon).
  bool settled = false;
};

/// The loop of one plant, simulated for any filtered PID (tf > 0, or kd = 0).
class LoopSimulator {
 public:
  /// `h_s` is the step wanted: the step used is the largest that divides the
  /// plant's dead time and is at most h_s.
  LoopSimulator(const Plant& plant, double h_s);
  double Step() const { return h_; }
  /// The response to `in` under `g`, for at most max_steps steps (and at
  /// least min_steps): it stops once y and u have been still for a delay
  /// and 50 steps (relative change under 1e-9 of their peaks).
  Response Run(const PidGains& g, const Inputs& in, int max_steps, int min_steps = 0) const;

 private:
  Eigen::MatrixXd a_;
  Eigen::VectorXd b_;
  Eigen::RowVectorXd c_;
  double d_ = 0.0;
  double h_ = 0.0;
  int delay_steps_ = 0;
};

/// \int|y - target|dt on the grid of step h (trapezoids, a sign change split
/// at its linear crossing).
double IntegralAbs(const std::vector<double>& y, double target, double h);

/// The plant's response G(jw) e^{-jwL} on a log grid.
struct FrequencyGrid {
  std::vector<double> w;
  std::vector<std::complex<double>> g;
  /// True where the delay's phase changes by more than 0.6 rad to the next
  /// point: there the peaks are bounded by |L| alone (|S| <= 1 / (1 - |L|)).
  std::vector<char> coarse;
  /// G at infinite frequency (the plant's feedthrough).
  double g_inf = 0.0;
};
FrequencyGrid MakeFrequencyGrid(const Plant& plant, double w_lo, double w_hi, double points_per_decade);

/// The peaks of |S|, |T| and |C S| on the grid (and at infinite frequency),
/// and the highest gain crossover (0: none).
struct Peaks {
  double ms = 0.0, mt = 0.0, noise_gain = 0.0, crossover = 0.0;
};
Peaks PeaksOf(const FrequencyGrid& grid, const PidGains& g);

/// C(jw) of the filtered PID.
std::complex<double> ControllerAt(const PidGains& g, double w);

}  // namespace pidlab::tune::design
