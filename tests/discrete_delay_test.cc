// The exact input delay of the sampled (ZOH) plant, G(s) e^(-sL): MATLAB's
// c2d example, an independent computation of Phi, Gamma0 and Gamma1, the
// undelayed plant's bits at L = 0, pure delays as shifts, continuity in L,
// a closed form, and the refused delays.

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/plant_sim/discrete_plant.h"
#include "pidlab/plant_sim/matrix_exp.h"
#include "pidlab/plant_sim/plants.h"
#include "pidlab/plant_sim/transfer_function.h"
#include "test_status.h"

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#endif
#include <unsupported/Eigen/MatrixFunctions>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace pidlab {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const TransferFunction kMatlabExample{{10.0}, {1.0, 3.0, 10.0}};  // c2d's documented example
const TransferFunction kFirstOrder{{1.0}, {1.0, 1.0}};

// The paper's built-in plants: double integrator, oscillator, stepper motor.
std::vector<Plant> PaperPlants() {
  std::vector<Plant> plants;
  for (const char* name : {"double_integrator", "oscillator", "stepper_motor"}) {
    Plant p;
    std::string error;
    if (!OkInto(MakePlant(name, StepperMotorParameters{}, &p), &error))
      ADD_FAILURE() << name << ": " << error;
    plants.push_back(p);
  }
  return plants;
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The outputs y_0 .. y_steps for the inputs u_0 .. u_{steps-1}.
std::vector<double> Response(DiscretePlant plant, const std::vector<double>& inputs) {
  std::vector<double> y;
  for (double u : inputs) {
    y.push_back(plant.Output());
    plant.Step(u);
  }
  y.push_back(plant.Output());
  return y;
}

std::vector<double> RandomInputs(int steps, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> dist(-2.0, 2.0);
  std::vector<double> u(static_cast<std::size_t>(steps));
  for (double& v : u) v = dist(rng);
  return u;
}

// x' = A x + B u with u(t) = u_{k-d} on [0, L') and u_{k-d+1} on [L', dt)
// of every step, by another route: Eigen's Pade matrix exponential and
// composite Gauss-Legendre quadrature of e^{As} B over [0, dt - L') and
// [dt - L', dt) directly.
struct Independent {
  Eigen::MatrixXd phi;
  Eigen::VectorXd gamma0, gamma1;
};

// Gauss-Legendre nodes and weights on [-1, 1] by Newton on P_n.
void GaussLegendre(int n, std::vector<double>* x, std::vector<double>* w) {
  x->assign(static_cast<std::size_t>(n), 0.0);
  w->assign(static_cast<std::size_t>(n), 0.0);
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(pi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-17) break;
    }
    (*x)[static_cast<std::size_t>(i)] = z;
    (*w)[static_cast<std::size_t>(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

Eigen::VectorXd IntegralOfExpB(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double from, double to) {
  std::vector<double> nodes, weights;
  GaussLegendre(10, &nodes, &weights);
  const int panels = 64;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(b.size());
  const double width = (to - from) / panels;
  for (int p = 0; p < panels; ++p) {
    const double mid = from + (p + 0.5) * width;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const double s = mid + 0.5 * width * nodes[i];
      const Eigen::MatrixXd e = (a * s).exp();
      sum += (0.5 * width * weights[i]) * (e * b);
    }
  }
  return sum;
}

Independent ComputeIndependently(const TransferFunction& tf, double dt, double delay) {
  const StateSpace ss = Realize(tf);
  const double d = std::ceil(delay / dt);
  const double late = delay - (d - 1.0) * dt;  // L'
  Independent r;
  r.phi = (ss.a * dt).exp();
  r.gamma0 = IntegralOfExpB(ss.a, ss.b, 0.0, dt - late);
  r.gamma1 = IntegralOfExpB(ss.a, ss.b, dt - late, dt);
  return r;
}

double RoundTo4Significant(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return std::stod(buf);
}

TEST(DelayedPlant, ReproducesMatlabsC2dExampleToFourSignificantFigures) {
  // MATLAB: c2d(tf(10, [1 3 10], 'InputDelay', 0.25), 0.1) =
  // z^-3 (0.01187 z^2 + 0.06408 z + 0.009721) / (z^2 - 1.655 z + 0.7408).
  const DiscretePlant plant(kMatlabExample, 0.1, 0.25);
  const DiscreteTransferFunction g = ZTransferFunction(plant);
  EXPECT_EQ(g.delay_steps, 3);
  ASSERT_EQ(g.num.size(), 3u);
  ASSERT_EQ(g.den.size(), 3u);
  const double num[] = {0.01187, 0.06408, 0.009721}, den[] = {1.0, -1.655, 0.7408};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(RoundTo4Significant(g.num[i]), num[i]) << "num[" << i << "] = " << g.num[i];
    EXPECT_EQ(RoundTo4Significant(g.den[i]), den[i]) << "den[" << i << "] = " << g.den[i];
  }
  std::printf("c2d example: z^-%ld (%.6g z^2 + %.6g z + %.6g) / (z^2 + %.6g z + %.6g)\n", g.delay_steps, g.num[0],
              g.num[1], g.num[2], g.den[1], g.den[2]);
}

TEST(DelayedPlant, TransferFunctionWithoutADelayIsTheUndelayedZohPlant) {
  // 1/(s+1) at dt: (1 - e^-dt) / (z - e^-dt), no leading numerator term.
  const double dt = 0.1;
  const DiscreteTransferFunction g = ZTransferFunction(DiscretePlant(kFirstOrder, dt));
  EXPECT_EQ(g.delay_steps, 0);
  ASSERT_EQ(g.num.size(), 2u);
  EXPECT_EQ(g.num[0], 0.0);
  EXPECT_NEAR(g.num[1], 1.0 - std::exp(-dt), 1e-15);
  EXPECT_NEAR(g.den[1], -std::exp(-dt), 1e-15);
}

TEST(DelayedPlant, PhiGamma0AndGamma1AgreeWithAnIndependentComputation) {
  struct Case {
    TransferFunction tf;
    double dt, delay;
  };
  std::vector<Case> cases = {{kMatlabExample, 0.1, 0.25}, {kMatlabExample, 0.1, 0.01}, {kMatlabExample, 0.1, 0.09},
                             {kFirstOrder, 0.1, 0.37}};
  for (const Plant& p : PaperPlants()) {
    cases.push_back({p.tf, 1e-3, 2.5e-3});
    cases.push_back({p.tf, 1e-3, 0.7e-3});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.tf.ToString() + " dt " + std::to_string(c.dt) + " L " + std::to_string(c.delay));
    const DiscretePlant plant(c.tf, c.dt, c.delay);
    ASSERT_TRUE(plant.delay().split);
    const Independent ref = ComputeIndependently(c.tf, c.dt, c.delay);
    // 1e-12 relative to the largest entry (the Gammas of the paper's plants
    // at 1 ms are far below 1).
    const double phi_scale = ref.phi.cwiseAbs().maxCoeff();
    const double gamma_scale = (ref.gamma0 + ref.gamma1).cwiseAbs().maxCoeff();
    EXPECT_LE((plant.phi() - ref.phi).cwiseAbs().maxCoeff(), 1e-12 * phi_scale);
    EXPECT_LE((plant.gamma0() - ref.gamma0).cwiseAbs().maxCoeff(), 1e-12 * gamma_scale);
    EXPECT_LE((plant.gamma1() - ref.gamma1).cwiseAbs().maxCoeff(), 1e-12 * gamma_scale);
    // The two pieces make up the undelayed Gamma.
    EXPECT_LE((plant.gamma0() + plant.gamma1() - plant.gamma()).cwiseAbs().maxCoeff(), 1e-12 * gamma_scale);
  }
}

TEST(DelayedPlant, ZeroDelayGivesTheUndelayedPlantsBitsOnThePapersPlants) {
  const std::vector<double> inputs = RandomInputs(3000, 7);
  for (const Plant& p : PaperPlants()) {
    SCOPED_TRACE(p.name);
    const double dt = 1e-3;
    const DiscretePlant undelayed(p.tf, dt), delayed(p.tf, dt, 0.0);
    EXPECT_EQ(delayed.delay_steps(), 0);
    EXPECT_FALSE(delayed.delay().split);
    EXPECT_EQ(delayed.gamma0().size(), 0);
    // The matrices of the plant before delays existed: Realize, then ZeroOrderHold over dt.
    const StateSpace ss = Realize(p.tf);
    Eigen::MatrixXd phi, gamma;
    ZeroOrderHold<double>(ss.a, Eigen::MatrixXd(ss.b), dt, &phi, &gamma);
    for (Eigen::Index i = 0; i < phi.rows(); ++i) {
      for (Eigen::Index j = 0; j < phi.cols(); ++j) EXPECT_TRUE(SameBits(delayed.phi()(i, j), phi(i, j)));
      EXPECT_TRUE(SameBits(delayed.gamma()(i), gamma(i, 0)));
      EXPECT_TRUE(SameBits(delayed.gamma1()(i), gamma(i, 0)));
    }
    // And its step: ZohStep on (phi, gamma), y = OutputOf(c, x).
    std::vector<double> x(static_cast<std::size_t>(ss.order()), 0.0), next = x, before;
    for (double u : inputs) {
      before.push_back(OutputOf(ss.c, x));
      ZohStep(phi, Eigen::VectorXd(gamma.col(0)), x, u, &next);
      x.swap(next);
    }
    before.push_back(OutputOf(ss.c, x));
    const std::vector<double> y0 = Response(undelayed, inputs), y1 = Response(delayed, inputs);
    for (std::size_t k = 0; k < before.size(); ++k) {
      ASSERT_TRUE(SameBits(y0[k], before[k])) << "k = " << k;
      ASSERT_TRUE(SameBits(y1[k], before[k])) << "k = " << k;
    }
  }
}

TEST(DelayedPlant, ADelayOfWholeStepsIsTheUndelayedOutputShiftedExactly) {
  const std::vector<double> inputs = RandomInputs(2000, 11);
  for (const Plant& p : PaperPlants()) {
    for (double dt : {1e-3, 0.1}) {
      if (p.name == "stepper_motor" && dt > 1e-3) continue;  // its poles want a short step
      const DiscretePlant undelayed(p.tf, dt);
      const std::vector<double> y = Response(undelayed, inputs);
      for (int m : {1, 2, 3, 7, 10}) {
        SCOPED_TRACE(p.name + " dt " + std::to_string(dt) + " m " + std::to_string(m));
        const DiscretePlant delayed(p.tf, dt, m * dt);  // m * dt as computed, rounding and all
        EXPECT_EQ(delayed.delay_steps(), m);
        EXPECT_FALSE(delayed.delay().split);
        const std::vector<double> yd = Response(delayed, inputs);
        for (int k = 0; k <= m; ++k) ASSERT_EQ(yd[static_cast<std::size_t>(k)], 0.0) << "k = " << k;
        for (std::size_t k = static_cast<std::size_t>(m); k < yd.size(); ++k)
          ASSERT_TRUE(SameBits(yd[k], y[k - static_cast<std::size_t>(m)])) << "k = " << k;
      }
    }
  }
}

TEST(DelayedPlant, StepResponseIsContinuousAcrossMultiplesOfTheStep) {
  struct Case {
    TransferFunction tf;
    double dt;
  };
  std::vector<Case> cases = {{kMatlabExample, 0.1}, {kFirstOrder, 0.1}};
  for (const Plant& p : PaperPlants()) cases.push_back({p.tf, 1e-3});
  const std::vector<double> step(400, 1.0);
  for (const Case& c : cases) {
    for (int k : {0, 1, 2, 3, 5}) {
      SCOPED_TRACE(c.tf.ToString() + " k " + std::to_string(k));
      const double at = k * c.dt;
      const std::vector<double> below =
          k == 0 ? Response(DiscretePlant(c.tf, c.dt, 0.0), step) : Response(DiscretePlant(c.tf, c.dt, at - 1e-12), step);
      const std::vector<double> exact = Response(DiscretePlant(c.tf, c.dt, at), step);
      const std::vector<double> above = Response(DiscretePlant(c.tf, c.dt, at + 1e-12), step);
      for (std::size_t i = 0; i < exact.size(); ++i) {
        ASSERT_NEAR(below[i], exact[i], 1e-9) << "i = " << i;
        ASSERT_NEAR(above[i], exact[i], 1e-9) << "i = " << i;
      }
    }
  }
}

TEST(DelayedPlant, FirstOrderLagStepResponseIsTheShiftedExponential) {
  // 1/(s+1) e^(-sL), unit step at t = 0: y(t) = 1 - e^-(t - L) for t >= L, 0 before.
  const double dt = 0.1;
  for (double delay : {0.3, 0.25, 0.05, 0.1, 1.234}) {
    SCOPED_TRACE("L " + std::to_string(delay));
    DiscretePlant plant(kFirstOrder, dt, delay);
    for (int k = 0; k <= 100; ++k) {
      const double t = k * dt;
      const double expected = t >= delay - 1e-15 ? 1.0 - std::exp(-(t - delay)) : 0.0;
      ASSERT_NEAR(plant.Output(), expected, 1e-12) << "k = " << k;
      plant.Step(1.0);
    }
  }
}

TEST(DelayedPlant, ResetEmptiesTheDelayLine) {
  DiscretePlant plant(kFirstOrder, 0.1, 0.25);
  for (int k = 0; k < 3; ++k) plant.Step(1.0);
  plant.Reset();
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(plant.Output(), 0.0) << "k = " << k;
    plant.Step(0.0);
  }
}

// The templated step a sampled loop calls: for double the same bits as
// DiscretePlant::Step, and for a Ceres Jet the same values.
template <typename T>
std::vector<T> TemplatedResponse(const DiscretePlant& plant, const std::vector<double>& inputs) {
  InputDelayLine<T> line(plant.delay_steps());
  std::vector<T> x(static_cast<std::size_t>(plant.order()), T(0.0)), next = x, y;
  for (double u : inputs) {
    y.push_back(OutputOf(plant.c(), x));
    DelayedPlantStep(plant, &line, x, T(u), &next);
    x.swap(next);
  }
  y.push_back(OutputOf(plant.c(), x));
  return y;
}

TEST(DelayedPlant, TemplatedLoopStepGivesTheSameBitsAsThePlant) {
  const std::vector<double> inputs = RandomInputs(1500, 3);
  for (const Plant& p : PaperPlants()) {
    for (double delay : {0.0, 1e-3, 2.5e-3, 0.4e-3, 17.3e-3}) {
      SCOPED_TRACE(p.name + " L " + std::to_string(delay));
      const DiscretePlant plant(p.tf, 1e-3, delay);
      const std::vector<double> y = Response(plant, inputs);
      const std::vector<double> yt = TemplatedResponse<double>(plant, inputs);
      const std::vector<ceres::Jet<double, 2>> yj = TemplatedResponse<ceres::Jet<double, 2>>(plant, inputs);
      ASSERT_EQ(y.size(), yt.size());
      for (std::size_t k = 0; k < y.size(); ++k) {
        ASSERT_TRUE(SameBits(y[k], yt[k])) << "k = " << k;
        ASSERT_TRUE(SameBits(y[k], yj[k].a)) << "k = " << k;
      }
    }
  }
}

TEST(DelayedPlant, SplitsTheDelayIntoWholeStepsAndAFraction) {
  const DelaySplit s = SplitDelay(0.25, 0.1);
  EXPECT_EQ(s.steps, 3);
  EXPECT_TRUE(s.split);
  EXPECT_NEAR(s.fraction_s, 0.05, 1e-15);
  const DelaySplit none = SplitDelay(0.0, 0.1);
  EXPECT_EQ(none.steps, 0);
  EXPECT_FALSE(none.split);
  const DelaySplit whole = SplitDelay(0.3, 0.1);  // 0.3 / 0.1 = 2.9999999999999996
  EXPECT_EQ(whole.steps, 3);
  EXPECT_FALSE(whole.split);
  const DelaySplit small = SplitDelay(1e-12, 0.1);
  EXPECT_EQ(small.steps, 1);
  EXPECT_TRUE(small.split);
}

void ExpectRefused(double delay, double dt, const std::string& named) {
  try {
    DiscretePlant(kFirstOrder, dt, delay);
    ADD_FAILURE() << "delay " << delay << " s at dt " << dt << " s was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
  }
}

TEST(DelayedPlant, RefusesANegativeNanInfiniteOrHugeDelayNamingIt) {
  ExpectRefused(-0.1, 0.1, "-0.1");
  ExpectRefused(-1e-300, 0.1, "-1e-300");
  ExpectRefused(kNaN, 0.1, "nan");
  ExpectRefused(kInf, 0.1, "inf");
  ExpectRefused(-kInf, 0.1, "-inf");
  ExpectRefused(2e6, 0.1, "2000000");
  ExpectRefused(1.5e6, 1e3, "1500000");
  // Within kMaxDelaySeconds but more than kMaxDelaySteps stored inputs.
  ExpectRefused(100.0, 1e-6, "100");
  ExpectRefused(1e-3, 1e-300, "0.001");
  // The step itself is still checked.
  EXPECT_THROW(DiscretePlant(kFirstOrder, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(DiscretePlant(kFirstOrder, kNaN, 0.1), std::invalid_argument);
  // At the limits: accepted.
  EXPECT_NO_THROW(DiscretePlant(kFirstOrder, 1.0, kMaxDelaySeconds));
  EXPECT_EQ(DiscretePlant(kFirstOrder, 1e-3, 1e4).delay_steps(), kMaxDelaySteps);
}

}  // namespace
}  // namespace pidlab
