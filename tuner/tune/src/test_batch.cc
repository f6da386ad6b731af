// The plants of the AMIGO test batch (batch.h; docs/deadtime.md, "The AMIGO
// test batch"): Astrom and Hagglund's families P1-P9 and their grids.

#include <algorithm>
#include <sstream>

#include "pidlab/plant_sim/polynomial.h"
#include "pidlab/tune/batch.h"

namespace pidlab::tune {
namespace {

std::string Label(const std::string& parameter, double value) {
  std::ostringstream os;
  os << parameter << " = " << value;
  return os.str();
}

// A plant gain K prod(-T0 s + 1) / (s^integrators prod(tau s + 1)) e^(-Ls).
BatchPlant Make(const std::string& family, const std::string& parameter, double value, FactoredPlant f,
                std::vector<double> den_lags, std::vector<double> extra_den = {1.0}) {
  BatchPlant p;
  p.family = family;
  p.parameter = parameter;
  p.value = value;
  p.label = Label(parameter, value);
  std::vector<double> num{f.gain};
  for (double t0 : f.inverse) num = PolynomialProduct(num, {-t0, 1.0});
  std::vector<double> den = PolynomialProduct(LagProduct(den_lags), extra_den);
  if (f.integrators == 1) den.push_back(0.0);
  p.plant.name = family + " " + p.label;
  p.plant.tf.num = num;
  p.plant.tf.den = den;
  p.plant.delay_s = f.delay_s;
  p.factors = std::move(f);
  return p;
}

FactoredPlant Factors(double gain, std::vector<double> lags, double delay_s, int integrators = 0,
                      std::vector<double> inverse = {}) {
  FactoredPlant f;
  f.gain = gain;
  f.lags = std::move(lags);
  f.delay_s = delay_s;
  f.integrators = integrators;
  f.inverse = std::move(inverse);
  return f;
}

const std::vector<double> kDelayFractions{0.01, 0.02, 0.05, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0};

void FirstAndSecondOrder(std::vector<BatchPlant>* out) {
  for (double t : {0.02, 0.05, 0.1, 0.2,  0.3,  0.5,  0.7,   1.0,   1.3,   1.5,   2.0,
                   4.0,  6.0,  8.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0})
    out->push_back(Make("P1", "T", t, Factors(1.0, {t}, 1.0), {t}));
  for (double t : {0.01, 0.02, 0.05, 0.1, 0.2,  0.3,  0.5,  0.7,   1.0,   1.3,  1.5,
                   2.0,  4.0,  6.0,  8.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0})
    out->push_back(Make("P2", "T", t, Factors(1.0, {t, t}, 1.0), {t, t}));
  for (double t : {0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 2.0, 5.0, 10.0})
    out->push_back(Make("P3", "T", t, Factors(1.0, {1.0, t, t}, 0.0), {1.0, t, t}));
  for (int n = 3; n <= 8; ++n) {
    const std::vector<double> lags(static_cast<std::size_t>(n), 1.0);
    out->push_back(Make("P4", "n", n, Factors(1.0, lags, 0.0), lags));
  }
  for (double a : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9}) {
    const std::vector<double> lags{1.0, a, a * a, a * a * a};
    out->push_back(Make("P5", "alpha", a, Factors(1.0, lags, 0.0), lags));
  }
}

void IntegratingAndOthers(std::vector<BatchPlant>* out) {
  for (double l1 : kDelayFractions) {
    const double t1 = 1.0 - l1;
    const std::vector<double> lags = t1 > 0.0 ? std::vector<double>{t1} : std::vector<double>{};
    out->push_back(Make("P6", "L1", l1, Factors(1.0, lags, l1, 1), lags));
  }
  for (double t : {1.0, 2.0, 5.0, 10.0})
    for (double l1 : kDelayFractions) {
      const double t1 = 1.0 - l1;
      std::vector<double> lags{t};
      if (t1 > 0.0) lags.push_back(t1);
      BatchPlant p = Make("P7", "L1", l1, Factors(t, lags, l1), lags);
      p.label = Label("T", t) + ", " + Label("L1", l1);
      p.plant.name = "P7 " + p.label;
      out->push_back(std::move(p));
    }
  for (double a : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1})
    out->push_back(Make("P8", "alpha", a, Factors(1.0, {1.0, 1.0, 1.0}, 0.0, 0, {a}), {1.0, 1.0, 1.0}));
  for (double t : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0}) {
    // (sT)^2 + 1.4 sT + 1 has damping 0.7; the half rule takes real poles, so
    // AMIGO's model reads it as (0.7 T s + 1)^2, the same sum of time constants.
    out->push_back(
        Make("P9", "T", t, Factors(1.0, {1.0, 0.7 * t, 0.7 * t}, 0.0), {1.0}, {t * t, 1.4 * t, 1.0}));
  }
}

}  // namespace

bool TestBatchPlants(const std::string& set, std::vector<BatchPlant>* plants) {
  if (set != "amigo") return false;
  plants->clear();
  FirstAndSecondOrder(plants);
  IntegratingAndOthers(plants);
  return true;
}

Status SelectFamilies(const std::vector<BatchPlant>& all, const std::vector<std::string>& families,
                      std::vector<BatchPlant>* selected) {
  selected->clear();
  for (const std::string& f : families)
    if (std::none_of(all.begin(), all.end(), [&f](const BatchPlant& p) { return p.family == f; }))
      return Status::InvalidInput("family '" + f + "' must be one of P1 ... P9");
  for (const BatchPlant& p : all)
    if (std::find(families.begin(), families.end(), p.family) != families.end()) selected->push_back(p);
  return Status::Ok();
}

}  // namespace pidlab::tune
