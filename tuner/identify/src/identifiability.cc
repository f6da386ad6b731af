// Which parameters of a fit the record does not identify (identify.h's
// IdentifyResult::not_identifiable; docs/identify.md, "Parameters the data
// do not identify"): at a bound of the fit, a lag too short to tell from a
// delay, or a time constant that ran beyond the record.

#include <cmath>
#include <limits>

#include "fit_problem.h"

namespace pidlab::identify::internal {
namespace {

// No standard error, or a 95 % interval wider than the value.
bool Undetermined(const IdentifyResult& r, std::size_t i) {
  if (!r.covariance_ok || i >= r.standard_errors.size()) return true;
  const double se = r.standard_errors[i];
  return !std::isfinite(se) || 1.96 * se > std::abs(r.values[i]);
}

std::string NoError(const IdentifyResult& r, std::size_t i) {
  if (!r.covariance_ok) return "no standard error";
  const double se = r.standard_errors[i];
  return std::isfinite(se) ? "a 95 % interval of +-" + Number(1.96 * se) + ", wider than it"
                           : "no standard error";
}

bool IsTimeConstant(const std::string& name) { return name == "Tp1" || name == "Tp2" || name == "Tw"; }

// The kind that describes the record without parameter `name` of `kind`:
// a lag that vanished (`vanished`) or one that ran beyond the record (an
// integrator). "" when no process kind does.
std::string SimplerKind(ProcessModelKind kind, const std::string& name, bool vanished) {
  ProcessModelKind inner;
  if (vanished) {
    if (name == "Tp1" && kind != ProcessModelKind::kP2DU) return "";  // Tp1 >= Tp2: both vanished
    return ContainedKind(kind, &inner) ? ToString(inner) : "";
  }
  if (name == "Zeta") return ToString(ProcessModelKind::kP2D);
  if (name == "Tp1" && (kind == ProcessModelKind::kP1D || kind == ProcessModelKind::kP2D))
    return ToString(ProcessModelKind::kP1DI);
  return "";
}

}  // namespace

std::vector<IdentifyResult::NotIdentifiable> NotIdentifiable(const Record& record, const IdentifyResult& r) {
  std::vector<IdentifyResult::NotIdentifiable> out;
  if (record.kind == ProcessModelKind::kTf) return out;
  const double long_s = kUnboundedRecordLengths * record.length_s;
  for (std::size_t i = 1; i < r.names.size() && i < r.values.size(); ++i) {
    const std::string& name = r.names[i];
    const double v = r.values[i];
    const std::string bound = i < r.at_bound.size() ? r.at_bound[i] : "";
    std::string reason;
    bool vanished = false;
    if (name == "Td") {
      // Td at 0 is a record without dead time, not an artefact of the fit.
      if (bound == "upper")
        reason = Number(v) + " s, at its upper bound " + Number(record.max_delay_s) + " s";
    } else if (name == "Zeta") {
      if (!bound.empty())
        reason = Number(v) + ", at its " + bound + " bound" +
                 (bound == "upper" ? " (1: the poles are real)" : " (an undamped oscillation)");
    } else if (!bound.empty()) {
      vanished = bound == "lower";
      reason =
          Number(v) + (name == "Tz" ? "" : " s") + ", at its " + bound + " bound " +
          Number(bound == "lower" ? record.dt_s / kTimeConstantRange : record.length_s * kTimeConstantRange) +
          " s";
    } else if (IsTimeConstant(name) && v < kUnresolvedLagOfDt * record.dt_s && Undetermined(r, i)) {
      vanished = true;
      reason = Number(v) + " s, under a tenth of dt = " + Number(record.dt_s) + " s, with " + NoError(r, i) +
               ": the record cannot tell it from a delay";
    } else if ((IsTimeConstant(name) || name == "Tz") && std::abs(v) > long_s) {
      reason = Number(v) + " s, beyond " + Number(kUnboundedRecordLengths) +
               " times the record's length: an unbounded optimum";
    }
    if (!reason.empty()) out.push_back({name, reason, SimplerKind(record.kind, name, vanished)});
  }
  if (record.kind == ProcessModelKind::kP2DZ && out.empty()) {
    // A zero whose 95 % interval holds a pole (or no interval): the pair
    // may cancel, and the record then shows the other lag alone.
    for (std::size_t j : {std::size_t{1}, std::size_t{2}}) {
      const double tz = r.values[3];
      const double half = r.covariance_ok && std::isfinite(r.standard_errors[3])
                              ? 1.96 * r.standard_errors[3]
                              : std::numeric_limits<double>::infinity();
      if (!(std::abs(tz - r.values[j]) <= half)) continue;
      out.push_back({"Tz",
                     Number(tz) + " s +- " + Number(half) + " (95 %), an interval holding " + r.names[j] +
                         " = " + Number(r.values[j]) +
                         " s: the pair may cancel, and the record show the other lag alone",
                     ToString(ProcessModelKind::kP1D)});
      break;
    }
  }
  return out;
}

std::string NotIdentifiableWarning(const IdentifyResult::NotIdentifiable& n, const IdentifyResult& r,
                                   const IdentifyResult* contained) {
  std::string w = n.parameter + " is not identifiable (" + n.reason + ")";
  if (n.simpler_model.empty()) return w;
  if (contained && ToString(contained->model.kind) == n.simpler_model && std::isfinite(contained->aic)) {
    const bool as_well = contained->aic <= r.aic + 2.0;
    return w + "; the " + n.simpler_model + " model fits " + (as_well ? "as well" : "worse") + " (AIC " +
           Number(contained->aic) + " against " + Number(r.aic) + ")";
  }
  return w + "; the " + n.simpler_model + " model may fit as well (--model " + n.simpler_model + ")";
}

}  // namespace pidlab::identify::internal
