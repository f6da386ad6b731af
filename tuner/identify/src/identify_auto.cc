// pidlab identify --model auto (identify.h's IdentifyAuto): every process
// kind fitted, at the rest the record implies and with one loss scale for
// all, and one chosen by AIC (docs/identify.md, "Choosing the model").

#include <cmath>
#include <iomanip>
#include <sstream>

#include "fit_problem.h"
#include "pidlab/identify/identify.h"
#include "pidlab/spec/field.h"

namespace pidlab::identify {
namespace {

constexpr ProcessModelKind kAutoKinds[] = {ProcessModelKind::kP1D, ProcessModelKind::kP2D,
                                           ProcessModelKind::kP2DU, ProcessModelKind::kP1DI,
                                           ProcessModelKind::kP2DZ};

// Why auto does not choose candidate `c` (AutoCandidate::set_aside), or
// "": a parameter the record does not identify, or its design's starts
// pruned by AIC against `lowest` (the kind of lowest AIC before it). No
// covariance alone is no reason: P2D's two equal lags (a double pole) have
// none, the pair identified but not which lag is which.
std::string SetAsideReason(const AutoCandidate& c, const AutoCandidate* lowest) {
  if (!c.status.ok()) return "";
  const IdentifyResult& r = c.result;
  if (!r.not_identifiable.empty()) {
    const IdentifyResult::NotIdentifiable& n = r.not_identifiable.front();
    return n.parameter + " is not identifiable (" + n.reason + ")" +
           (n.simpler_model.empty() ? "" : "; " + n.simpler_model + " describes the record without it");
  }
  if (r.starts_skipped > 0 && lowest)
    return "pruned by AIC: after " + std::to_string(r.starts) + " starts its AIC " + internal::Number(r.aic) +
           " was more than " + internal::Number(internal::kPruneAic) + " above " + ToString(lowest->kind) +
           "'s " + internal::Number(lowest->result.aic) + ", so its other " +
           std::to_string(r.starts_skipped) + " starts were not run";
  return "";
}

// The candidate of lowest AIC among those not set aside; nullptr if none.
const AutoCandidate* Lowest(const std::vector<AutoCandidate>& candidates) {
  const AutoCandidate* lowest = nullptr;
  for (const AutoCandidate& c : candidates)
    if (c.status.ok() && c.set_aside.empty() && std::isfinite(c.result.aic) &&
        (!lowest || c.result.aic < lowest->result.aic))
      lowest = &c;
  return lowest;
}

// Every kind at u0 as the options give it, each from the optimum of the
// kind it contains (fitted before it) and of the same kind in `prior` (the
// l2 fits before robust ones; nullptr: none), its design's starts pruned by
// AIC against the kinds before it (internal::Seeds::aic_to_beat).
Status FitCandidates(const IdentifyData& data, const IdentifyOptions& options, const AutoResult* prior,
                     std::vector<AutoCandidate>* candidates) {
  candidates->clear();
  for (ProcessModelKind kind : kAutoKinds) {
    AutoCandidate c;
    c.kind = kind;
    internal::Seeds seeds;
    ProcessModelKind inner;
    for (const AutoCandidate& before : *candidates)
      if (internal::ContainedKind(kind, &inner) && before.kind == inner && before.status.ok())
        seeds.contained = &before.result;
    for (std::size_t i = 0; prior && i < prior->candidates.size(); ++i)
      if (prior->candidates[i].kind == kind && prior->candidates[i].status.ok())
        seeds.same_kind = &prior->candidates[i].result;
    const AutoCandidate* lowest = Lowest(*candidates);
    if (lowest) seeds.aic_to_beat = lowest->result.aic;
    c.status = internal::FitKind(data, kind, options, seeds, &c.result);
    // Bad data or options are the same for every kind: say it once.
    if (c.status.code() == StatusCode::kInvalidInput) return c.status;
    c.set_aside = SetAsideReason(c, lowest);
    candidates->push_back(std::move(c));
  }
  return Status::Ok();
}

// The candidates at the rest the record implies: fitted at rest under u[0]
// and at rest at u = 0 when Identify would fit both, each kind keeping the
// lower AIC.
Status FitCandidatesAtRest(const IdentifyData& data, const IdentifyOptions& options, const AutoResult* prior,
                           std::vector<AutoCandidate>* candidates) {
  if (!internal::RestsToChoose(data, options)) return FitCandidates(data, options, prior, candidates);
  IdentifyOptions at_first = options, at_zero = options;
  at_first.u0 = data.u[0];
  at_zero.u0 = 0.0;
  std::vector<AutoCandidate> first, zero;
  if (Status s = FitCandidates(data, at_first, prior, &first); !s.ok()) return s;
  if (Status s = FitCandidates(data, at_zero, prior, &zero); !s.ok()) return s;
  candidates->clear();
  for (std::size_t i = 0; i < first.size(); ++i) {
    AutoCandidate c;
    c.kind = first[i].kind;
    c.status = internal::ChooseRest(data.u[0], first[i].status, &first[i].result, zero[i].status,
                                    &zero[i].result, &c.result);
    c.set_aside = (c.result.rest_hypotheses.size() == 2 && c.result.u0 == 0.0 ? zero[i] : first[i]).set_aside;
    candidates->push_back(std::move(c));
  }
  return Status::Ok();
}

// The kind of lowest AIC, or the simplest within 2 of it, and why.
Status ChooseKind(AutoResult* result) {
  // The lowest AIC; then, among the kinds within 2 of it (which the data
  // hardly tell apart, Burnham & Anderson), the one of fewest parameters.
  int lowest = -1;
  const auto aic = [&](int i) { return result->candidates[static_cast<std::size_t>(i)].result.aic; };
  const auto usable = [&](int i) {
    const AutoCandidate& c = result->candidates[static_cast<std::size_t>(i)];
    return c.status.ok() && c.set_aside.empty() && std::isfinite(c.result.aic);
  };
  const int count = static_cast<int>(result->candidates.size());
  for (int i = 0; i < count; ++i)
    if (usable(i) && (lowest < 0 || aic(i) < aic(lowest))) lowest = i;
  if (lowest < 0) {
    std::string why;
    for (const AutoCandidate& c : result->candidates)
      if (why.empty() && (!c.status.ok() || !c.set_aside.empty()))
        why = std::string(ToString(c.kind)) +
              (c.status.ok() ? " set aside: " + c.set_aside : ": " + c.status.message());
    return Status::RunnerFailed("no model kind could be fitted (p1d, p2d, p2du, p1di and p2dz tried" +
                                (why.empty() ? std::string(")") : "; " + spec::Truncate(why, 150) + ")"));
  }
  const auto parameters = [&](int i) {
    return result->candidates[static_cast<std::size_t>(i)].result.names.size();
  };
  result->chosen = lowest;
  for (int i = 0; i < count; ++i)
    if (usable(i) && aic(i) < aic(lowest) + 2.0 &&
        (parameters(i) < parameters(result->chosen) ||
         (parameters(i) == parameters(result->chosen) && aic(i) < aic(result->chosen))))
      result->chosen = i;
  const AutoCandidate& best = result->candidates[static_cast<std::size_t>(result->chosen)];
  std::ostringstream os;
  os << std::setprecision(6);
  if (result->chosen == lowest) {
    // The runner-up: the next lowest AIC.
    int next = -1;
    for (int i = 0; i < count; ++i)
      if (i != lowest && usable(i) && (next < 0 || aic(i) < aic(next))) next = i;
    os << ToString(best.kind) << " has the lowest AIC (" << best.result.aic << ", fit "
       << best.result.fit_percent << " %)";
    if (next >= 0) {
      const double delta = aic(next) - aic(lowest);
      os << "; the next, " << ToString(result->candidates[static_cast<std::size_t>(next)].kind) << ", is "
         << delta << " higher";
      if (delta < 2.0)
        os << " (less than 2, but it has more parameters)";
      else if (delta > 10.0)
        os << " (more than 10: the data rule it out)";
    }
  } else {
    os << ToString(best.kind) << " (AIC " << best.result.aic << ", fit " << best.result.fit_percent
       << " %) is within 2 of the lowest AIC, "
       << ToString(result->candidates[static_cast<std::size_t>(lowest)].kind) << "'s " << aic(lowest)
       << ", with fewer parameters (" << best.result.names.size() << " against " << parameters(lowest)
       << "): the data hardly tell them apart, so the simpler is kept";
  }
  std::string aside;
  for (const AutoCandidate& c : result->candidates)
    if (!c.set_aside.empty()) aside += (aside.empty() ? "" : ", ") + std::string(ToString(c.kind));
  if (!aside.empty()) os << "; set aside: " << aside;
  result->reason = os.str();
  return Status::Ok();
}

}  // namespace

Status IdentifyAuto(const IdentifyData& data, const IdentifyOptions& given, AutoResult* result) {
  *result = AutoResult{};
  // A long record's starts on a shorter copy, the best of each kind refitted
  // on all of it (IdentifyOptions::start_samples, as for a decimated record).
  IdentifyOptions options = given;
  if (options.start_samples == 0 && data.y.size() > kAutoStartSamples)
    options.start_samples = kAutoStartSamples;
  if (options.loss == Loss::kL2 || !std::isnan(options.loss_scale)) {
    if (Status s = FitCandidatesAtRest(data, options, nullptr, &result->candidates); !s.ok()) return s;
    return ChooseKind(result);
  }
  // A robust loss without its scale: one scale for every kind (so that
  // their AICs compare), from the residuals of the l2 fit auto chooses.
  if (std::string error; !options.IsValid(&error)) return Status::InvalidInput(error);
  IdentifyOptions l2 = options;
  l2.loss = Loss::kL2;
  AutoResult least_squares;
  if (Status s = IdentifyAuto(data, l2, &least_squares); !s.ok()) return s;
  IdentifyOptions robust = options;
  std::string source;
  robust.loss_scale = internal::DerivedLossScale(
      options.loss, least_squares.candidates[static_cast<std::size_t>(least_squares.chosen)].result.residuals,
      data.y, &source);
  if (Status s = FitCandidatesAtRest(data, robust, &least_squares, &result->candidates); !s.ok()) return s;
  for (AutoCandidate& c : result->candidates) c.result.loss_scale_source = source;
  return ChooseKind(result);
}

}  // namespace pidlab::identify
