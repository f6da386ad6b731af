// The process models of MATLAB's idproc (process_model.h).

#include "pidlab/plant_sim/process_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pidlab::plant_sim {

const char* ToString(ProcessModelKind kind) {
  switch (kind) {
    case ProcessModelKind::kP1D:
      return "p1d";
    case ProcessModelKind::kP2D:
      return "p2d";
    case ProcessModelKind::kP2DU:
      return "p2du";
    case ProcessModelKind::kP1DI:
      return "p1di";
    case ProcessModelKind::kP2DZ:
      return "p2dz";
    case ProcessModelKind::kTf:
      return "tf";
  }
  return "unknown";
}

bool Parse(const std::string& text, ProcessModelKind* kind) {
  for (ProcessModelKind k : {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU,
                             ProcessModelKind::kP1DI, ProcessModelKind::kP2DZ, ProcessModelKind::kTf}) {
    if (text == ToString(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

std::string ProcessModelKindNames() { return "p1d|p2d|p2du|p1di|p2dz|tf"; }

namespace {

bool TfShapeIsValid(int poles, int zeros) {
  return poles >= 1 && poles <= kMaxTfPoles && zeros >= 0 && zeros < poles;
}

}  // namespace

TransferFunction ProcessModel::ToTransferFunction() const {
  switch (kind) {
    case ProcessModelKind::kP1D:
      return {{kp}, {tp1_s, 1.0}};
    case ProcessModelKind::kP2D:
      return {{kp}, {tp1_s * tp2_s, tp1_s + tp2_s, 1.0}};
    case ProcessModelKind::kP2DU:
      return {{kp}, {tw_s * tw_s, 2.0 * zeta * tw_s, 1.0}};
    case ProcessModelKind::kP1DI:
      return {{kp}, {tp1_s, 1.0, 0.0}};
    case ProcessModelKind::kP2DZ:
      if (tz_s == 0.0) return {{kp}, {tp1_s * tp2_s, tp1_s + tp2_s, 1.0}};
      return {{kp * tz_s, kp}, {tp1_s * tp2_s, tp1_s + tp2_s, 1.0}};
    case ProcessModelKind::kTf: {
      TransferFunction tf{{b.rbegin(), b.rend()}, {1.0}};
      tf.den.insert(tf.den.end(), a.rbegin(), a.rend());
      return tf;
    }
  }
  return {};
}

std::vector<std::string> ParameterNames(ProcessModelKind kind, int poles, int zeros) {
  switch (kind) {
    case ProcessModelKind::kP1D:
    case ProcessModelKind::kP1DI:
      return {"Kp", "Tp1", "Td"};
    case ProcessModelKind::kP2D:
      return {"Kp", "Tp1", "Tp2", "Td"};
    case ProcessModelKind::kP2DU:
      return {"Kp", "Tw", "Zeta", "Td"};
    case ProcessModelKind::kP2DZ:
      return {"Kp", "Tp1", "Tp2", "Tz", "Td"};
    case ProcessModelKind::kTf: {
      if (!TfShapeIsValid(poles, zeros)) return {};
      std::vector<std::string> names;
      for (int i = 0; i <= zeros; ++i) names.push_back("b" + std::to_string(i));
      for (int i = 0; i < poles; ++i) names.push_back("a" + std::to_string(i));
      names.push_back("Td");
      return names;
    }
  }
  return {};
}

std::vector<double> ParameterValues(const ProcessModel& m) {
  switch (m.kind) {
    case ProcessModelKind::kP1D:
    case ProcessModelKind::kP1DI:
      return {m.kp, m.tp1_s, m.td_s};
    case ProcessModelKind::kP2D:
      return {m.kp, m.tp1_s, m.tp2_s, m.td_s};
    case ProcessModelKind::kP2DU:
      return {m.kp, m.tw_s, m.zeta, m.td_s};
    case ProcessModelKind::kP2DZ:
      return {m.kp, m.tp1_s, m.tp2_s, m.tz_s, m.td_s};
    case ProcessModelKind::kTf: {
      std::vector<double> values = m.b;
      values.insert(values.end(), m.a.begin(), m.a.end());
      values.push_back(m.td_s);
      return values;
    }
  }
  return {};
}

ProcessModel ModelFromValues(ProcessModelKind kind, const std::vector<double>& v, int poles, int zeros) {
  ProcessModel m;
  m.kind = kind;
  m.kp = v.at(0);
  m.td_s = v.back();
  switch (kind) {
    case ProcessModelKind::kTf: {
      const auto nb = static_cast<std::size_t>(zeros + 1), na = static_cast<std::size_t>(poles);
      if (!TfShapeIsValid(poles, zeros) || v.size() != nb + na + 1)
        throw std::invalid_argument("tf: " + std::to_string(v.size()) + " values do not fit " +
                                    std::to_string(poles) + " poles and " + std::to_string(zeros) + " zeros");
      m.kp = 1.0;
      m.poles = poles;
      m.zeros = zeros;
      m.b.assign(v.begin(), v.begin() + static_cast<long>(nb));
      m.a.assign(v.begin() + static_cast<long>(nb), v.begin() + static_cast<long>(nb + na));
      break;
    }
    case ProcessModelKind::kP1D:
    case ProcessModelKind::kP1DI:
      m.tp1_s = v.at(1);
      break;
    case ProcessModelKind::kP2D:
      m.tp1_s = v.at(1);
      m.tp2_s = v.at(2);
      break;
    case ProcessModelKind::kP2DU:
      m.tw_s = v.at(1);
      m.zeta = v.at(2);
      break;
    case ProcessModelKind::kP2DZ:
      m.tp1_s = v.at(1);
      m.tp2_s = v.at(2);
      m.tz_s = v.at(3);
      break;
  }
  return m;
}

bool IsHurwitz(const std::vector<double>& a) {
  const std::size_t n = a.size();
  if (n == 0) return false;
  // The Routh array's first two rows from the descending coefficients 1,
  // a_(n-1), ..., a_0; every later row from the two above it. Stable iff
  // the n + 1 entries of its first column are positive.
  std::vector<double> c = {1.0};
  c.insert(c.end(), a.rbegin(), a.rend());
  std::vector<double> upper, lower;
  for (std::size_t i = 0; i <= n; i += 2) upper.push_back(c[i]);
  for (std::size_t i = 1; i <= n; i += 2) lower.push_back(c[i]);
  for (std::size_t row = 1; row <= n; ++row) {
    if (lower.empty() || !(lower[0] > 0.0)) return false;
    std::vector<double> next;
    for (std::size_t j = 0; j + 1 < upper.size(); ++j)
      next.push_back(upper[j + 1] - upper[0] * (j + 1 < lower.size() ? lower[j + 1] : 0.0) / lower[0]);
    upper = std::move(lower);
    lower = std::move(next);
  }
  return true;
}

bool ParametersAreValid(ProcessModelKind kind, const std::vector<double>& values, std::string* error,
                        int poles, int zeros) {
  std::ostringstream os;
  if (kind == ProcessModelKind::kTf && !TfShapeIsValid(poles, zeros)) {
    os << "tf with " << poles << " poles and " << zeros << " zeros: poles must be in 1.." << kMaxTfPoles
       << " and zeros in 0..poles-1";
    if (error) *error = os.str();
    return false;
  }
  const std::vector<std::string> names = ParameterNames(kind, poles, zeros);
  if (values.size() != names.size()) {
    os << ToString(kind) << " has " << names.size() << " parameters, not " << values.size();
  } else {
    for (std::size_t i = 0; i < values.size() && os.tellp() == 0; ++i) {
      const std::string& name = names[i];
      const double v = values[i];
      if (!std::isfinite(v))
        os << name << " " << v << " must be finite";
      else if ((name == "Tp1" || name == "Tp2" || name == "Tw") && !(v > 0.0))
        os << name << " " << v << " s must be > 0";
      else if (name == "Zeta" && !(v > 0.0 && v < 1.0))
        os << "Zeta " << v << " must be in (0, 1)";
      else if (name == "Td" && !(v >= 0.0))
        os << "Td " << v << " s must be >= 0";
    }
    if (os.tellp() == 0 && kind == ProcessModelKind::kTf) {
      const auto nb = static_cast<long>(zeros + 1);
      const std::vector<double> a(values.begin() + nb, values.end() - 1);
      if (std::all_of(values.begin(), values.begin() + nb, [](double v) { return v == 0.0; }))
        os << "the numerator b0 .. b" << zeros << " is zero";
      else if (!IsHurwitz(a))
        os << "the denominator has a root with a real part >= 0 (an unstable or marginal tf)";
    }
    if (os.tellp() == 0) return true;
  }
  if (error) *error = os.str();
  return false;
}

}  // namespace pidlab::plant_sim
