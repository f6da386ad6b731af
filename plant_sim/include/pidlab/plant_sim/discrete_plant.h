#pragma once
// A plant discretised exactly (zero-order hold) at a fixed step, optionally
// with an input delay (dead time) G(s) e^(-sL): what the plant process and
// the in-process sampled loop both run, so their trajectories agree bit for
// bit. docs/deadtime.md, "The sampled loop", derives the delayed step.

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "pidlab/plant_sim/transfer_function.h"

namespace pidlab {

/// Limits of the input delay: L at most kMaxDelaySeconds, and at most
/// kMaxDelaySteps stored inputs d = ceil(L / dt) (a delay line of d doubles,
/// 80 MB at the bound).
inline constexpr double kMaxDelaySeconds = 1e6;
inline constexpr long kMaxDelaySteps = 10'000'000;

/// One exact ZOH step, next = phi x + gamma input, in a fixed summation order.
/// Shared by DiscretePlant and the templated sampled loop so that both give
/// the same bits for double.
template <typename T>
void ZohStep(const Eigen::MatrixXd& phi, const Eigen::VectorXd& gamma, const std::vector<T>& x,
             const T& input, std::vector<T>* next) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < n; ++i) {
    T acc = T(0.0);
    for (std::size_t j = 0; j < n; ++j)
      acc += phi(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
    (*next)[i] = acc + gamma(static_cast<Eigen::Index>(i)) * input;
  }
}

/// One exact ZOH step of the delayed plant,
///   next = phi x + gamma1 u_{k-d} + gamma0 u_{k-d+1},
/// summed in a fixed order: ((phi x)_i + gamma1_i u_{k-d}) + gamma0_i u_{k-d+1},
/// (phi x)_i summed over j ascending. An empty gamma0 means the step is not
/// split (L a multiple of dt, L = 0 included): then this is exactly
/// ZohStep(phi, gamma1, x, u_{k-d}), the same bits. `oldest` is u_{k-d},
/// `next_oldest` u_{k-d+1} (InputDelayLine::Push gives both).
template <typename T>
void DelayedZohStep(const Eigen::MatrixXd& phi, const Eigen::VectorXd& gamma1, const Eigen::VectorXd& gamma0,
                    const std::vector<T>& x, const T& oldest, const T& next_oldest, std::vector<T>* next) {
  if (gamma0.size() == 0) {
    ZohStep(phi, gamma1, x, oldest, next);
    return;
  }
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < n; ++i) {
    T acc = T(0.0);
    for (std::size_t j = 0; j < n; ++j)
      acc += phi(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
    const Eigen::Index row = static_cast<Eigen::Index>(i);
    (*next)[i] = (acc + gamma1(row) * oldest) + gamma0(row) * next_oldest;
  }
}

/// The d most recent plant inputs u_{k-d} .. u_{k-1} (zero before t = 0), a
/// ring buffer. Templated on the scalar like the sampled loop.
template <typename T>
class InputDelayLine {
 public:
  /// `steps` = d >= 0 (DiscretePlant::delay_steps()).
  explicit InputDelayLine(long steps = 0) : past_(static_cast<std::size_t>(steps), T(0.0)) {}

  /// Takes u_k; sets *oldest = u_{k-d} and *next_oldest = u_{k-d+1} (u_k
  /// itself when d = 1; both u_k when d = 0), then stores u_k.
  void Push(const T& input, T* oldest, T* next_oldest) {
    const std::size_t d = past_.size();
    if (d == 0) {
      *oldest = input;
      *next_oldest = input;
      return;
    }
    const std::size_t second = head_ + 1 == d ? 0 : head_ + 1;
    *oldest = past_[head_];
    *next_oldest = d == 1 ? input : past_[second];
    past_[head_] = input;
    head_ = second;
  }
  void Reset() {
    std::fill(past_.begin(), past_.end(), T(0.0));
    head_ = 0;
  }
  long steps() const { return static_cast<long>(past_.size()); }

 private:
  std::vector<T> past_;
  std::size_t head_ = 0;  // where u_{k-d} is
};

/// y = c x in a fixed summation order.
template <typename T>
T OutputOf(const Eigen::RowVectorXd& c, const std::vector<T>& x) {
  T y = T(0.0);
  for (std::size_t i = 0; i < x.size(); ++i) y += c(static_cast<Eigen::Index>(i)) * x[i];
  return y;
}

/// The split of an input delay L over steps of dt: L = (d - 1) dt + L' with
/// 0 < L' <= dt, so d = ceil(L / dt); L = 0 is d = 0 (L' = dt, no split). A
/// delay within a few rounding errors of a multiple m dt (|L/dt - m| <= 8 eps
/// max(1, m)) is taken as that multiple, so that m * dt computed in floating
/// point is the pure m-step delay. `split` is false when L' = dt.
struct DelaySplit {
  long steps = 0;            // d
  double fraction_s = 0.0;   // L' (dt when not split)
  bool split = false;        // 0 < L' < dt
};
/// Throws std::invalid_argument naming the value if delay_s is negative, not
/// finite or above kMaxDelaySeconds, or d above kMaxDelaySteps; dt_s must be
/// positive and finite (checked the same way).
DelaySplit SplitDelay(double delay_s, double dt_s);

/// The exact ZOH discretisation of x' = A x + B u(t - L):
///   x_{k+1} = phi x_k + gamma1 u_{k-d} + gamma0 u_{k-d+1},
/// phi = e^{A dt}, gamma0 = int_0^{dt-L'} e^{As} ds B,
/// gamma1 = e^{A(dt-L')} int_0^{L'} e^{As} ds B. Without a split gamma0 is
/// empty and gamma1 is ZeroOrderHold's gamma over dt (the same bits).
/// docs/deadtime.md derives it. DelayedZeroOrderHold throws as SplitDelay.
struct DelayedZoh {
  DelaySplit delay;
  Eigen::MatrixXd phi;
  Eigen::VectorXd gamma;  // the undelayed ZOH Gamma over dt (ZeroOrderHold's)
  Eigen::VectorXd gamma1;
  Eigen::VectorXd gamma0;
};
DelayedZoh DelayedZeroOrderHold(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double dt_s, double delay_s);

class DiscretePlant {
 public:
  /// Throws std::invalid_argument if `tf` is invalid or not strictly proper
  /// (a direct feedthrough would make the sampled loop algebraic), or if dt_s
  /// is not positive and finite.
  DiscretePlant(const TransferFunction& tf, double dt_s);
  /// The plant with an input delay of delay_s seconds, G(s) e^(-s delay_s).
  /// delay_s = 0 is the plant above, bit for bit. Throws as SplitDelay too.
  DiscretePlant(const TransferFunction& tf, double dt_s, double delay_s);

  /// y_k = C x_k, the output at the start of the current step.
  double Output() const;
  /// x_{k+1} = Phi x_k + Gamma u_k, with u_k the total plant input (control
  /// plus disturbance) held over the step; with a delay, x_{k+1} = Phi x_k +
  /// Gamma1 u_{k-d} + Gamma0 u_{k-d+1} (DelayedZohStep). Fixed summation order.
  void Step(double input);
  /// State and delay line to zero.
  void Reset();

  int order() const { return static_cast<int>(state_.size()); }
  double dt_s() const { return dt_s_; }
  double delay_s() const { return delay_s_; }
  /// d, the number of stored past inputs (0 without a delay).
  long delay_steps() const { return delay_.steps; }
  const DelaySplit& delay() const { return delay_; }
  const Eigen::MatrixXd& phi() const { return phi_; }
  /// The ZOH Gamma of the undelayed plant over dt (as before delays existed).
  const Eigen::VectorXd& gamma() const { return gamma_; }
  /// The delayed step's Gamma1 (on u_{k-d}) and Gamma0 (on u_{k-d+1}, empty
  /// without a split). Without a delay gamma1() == gamma(), bit for bit.
  const Eigen::VectorXd& gamma1() const { return gamma1_; }
  const Eigen::VectorXd& gamma0() const { return gamma0_; }
  const Eigen::RowVectorXd& c() const { return c_; }
  const std::vector<double>& state() const { return state_; }

 private:
  double dt_s_;
  double delay_s_ = 0.0;
  DelaySplit delay_;
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma_;
  Eigen::VectorXd gamma1_;
  Eigen::VectorXd gamma0_;
  Eigen::RowVectorXd c_;
  std::vector<double> state_;
  std::vector<double> next_;
  InputDelayLine<double> line_;
};

/// One step of a sampled loop over `plant` with its delay line `line`
/// (InputDelayLine<T>(plant.delay_steps()), zero at the start): pushes
/// `input` = u_k and sets *next = x_{k+1}. DiscretePlant::Step is this for
/// double, so a templated loop calling it gives DiscretePlant's bits.
template <typename T>
void DelayedPlantStep(const DiscretePlant& plant, InputDelayLine<T>* line, const std::vector<T>& x,
                      const T& input, std::vector<T>* next) {
  T oldest = input, next_oldest = input;
  line->Push(input, &oldest, &next_oldest);
  DelayedZohStep(plant.phi(), plant.gamma1(), plant.gamma0(), x, oldest, next_oldest, next);
}

/// The delayed ZOH plant as a transfer function in z, for checking:
/// z^-d num(z) / den(z), descending powers of z, den = det(zI - Phi) (monic,
/// order + 1 coefficients), num = C adj(zI - Phi) (Gamma0 z + Gamma1) (order
/// + 1 coefficients; the leading one is 0 without a split). MATLAB's c2d of
/// the plant with InputDelay = delay_s gives the same. By Faddeev-LeVerrier,
/// accurate for the low orders of the built-in plants.
struct DiscreteTransferFunction {
  long delay_steps = 0;
  std::vector<double> num;
  std::vector<double> den;
};
DiscreteTransferFunction ZTransferFunction(const DiscretePlant& plant);

}  // namespace pidlab
