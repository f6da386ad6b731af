#include "pidlab/tune/search_box.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pidlab/tune/tune.h"
#include "pidlab/tune/tuning_rules.h"
#include "spec_build.h"

namespace pidlab::tune {

Status PlantSearchBox(const Plant& plant, SearchBox* box) {
  *box = SearchBox();
  if (plant.nonlinear) return Status::InvalidInput("a nonlinear plant has no AMIGO model");
  TuningRuleResult rule;
  const Status status = ApplyTuningRule(plant, TuningRule::kAmigo, RuleForm::kPid, &rule);
  if (!status.ok()) {
    box->message = "the paper's box [0, 30]: " + status.message();
    return status;
  }
  const PidGains& g = rule.gains;
  const double largest = std::max({g.kp, g.ki, g.kd});
  const double upper = kPlantBoxFactor * largest;
  if (!std::isfinite(upper) || !(upper > 0.0) || upper > kMaxGain) {
    box->message = "the paper's box [0, 30]: AMIGO's gains give no finite box";
    return Status::InvalidInput(box->message);
  }
  box->upper = upper;
  box->source = "plant";
  std::ostringstream os;
  os << "[0, " << upper << "] = " << kPlantBoxFactor << " x the largest gain of " << rule.message;
  box->message = os.str();
  return Status::Ok();
}

SearchBox ResolveSearchBox(spec::TuningSpec* s, const std::set<std::string>& given) {
  SearchBox box;
  if (given.count("bounds") > 0) {
    box.lower = s->tune.bounds.first;
    box.upper = s->tune.bounds.second;
    box.source = "given";
    box.message = "the box given";
    return box;
  }
  box.lower = s->tune.bounds.first;
  box.upper = s->tune.bounds.second;
  TuneMethod method;
  if (!ParseTuneMethod(s->tune.method, &method) || IsTuningRule(method)) return box;
  Plant plant;
  std::string error;
  if (!BuildPlant(s->plant, NameStyle::kFlag, &plant, &error)) return box;
  SearchBox derived;
  if (!PlantSearchBox(plant, &derived).ok()) {
    box.message = derived.message;
    return box;
  }
  s->tune.bounds = {derived.lower, derived.upper};
  return derived;
}

std::vector<std::string> GainsAtBounds(const PidGains& g, double lower, double upper) {
  const double tolerance = 1e-6 * (upper - lower);
  std::vector<std::string> at;
  const std::pair<const char*, double> gains[] = {{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}};
  for (const auto& [name, value] : gains) {
    if (value <= lower + tolerance) at.push_back(std::string(name) + "_lo");
    if (value >= upper - tolerance) at.push_back(std::string(name) + "_hi");
  }
  return at;
}

}  // namespace pidlab::tune
