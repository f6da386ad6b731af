#include "pidlab/identify/process_model.h"

namespace pidlab::identify {

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
  }
  return "unknown";
}

bool Parse(const std::string& text, ProcessModelKind* kind) {
  for (ProcessModelKind k :
       {ProcessModelKind::kP1D, ProcessModelKind::kP2D, ProcessModelKind::kP2DU, ProcessModelKind::kP1DI}) {
    if (text == ToString(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

std::string ProcessModelKindNames() { return "p1d|p2d|p2du|p1di"; }

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
  }
  return m;
}

}  // namespace pidlab::identify
