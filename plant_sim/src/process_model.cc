// The process models of MATLAB's idproc (process_model.h).

#include "pidlab/plant_sim/process_model.h"

#include <cmath>
#include <sstream>

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
  }
  return "unknown";
}

bool Parse(const std::string& text, ProcessModelKind* kind) {
  for (ProcessModelKind k : {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU,
                             ProcessModelKind::kP1DI, ProcessModelKind::kP2DZ}) {
    if (text == ToString(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

std::string ProcessModelKindNames() { return "p1d|p2d|p2du|p1di|p2dz"; }

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
  }
  return {};
}

std::vector<std::string> ParameterNames(ProcessModelKind kind) {
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
  }
  return {};
}

ProcessModel ModelFromValues(ProcessModelKind kind, const std::vector<double>& v) {
  ProcessModel m;
  m.kind = kind;
  m.kp = v.at(0);
  m.td_s = v.back();
  switch (kind) {
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

bool ParametersAreValid(ProcessModelKind kind, const std::vector<double>& values, std::string* error) {
  const std::vector<std::string> names = ParameterNames(kind);
  std::ostringstream os;
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
    if (os.tellp() == 0) return true;
  }
  if (error) *error = os.str();
  return false;
}

}  // namespace pidlab::plant_sim
