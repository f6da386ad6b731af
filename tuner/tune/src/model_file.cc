// An identified model as a plant (model_file.h).

#include "pidlab/tune/model_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/io/files.h"
#include "pidlab/plant_sim/process_model.h"
#include "pidlab/spec/field.h"
#include "pidlab/spec/json.h"

namespace pidlab::tune {

using plant_sim::ParameterNames;
using plant_sim::ParametersAreValid;
using plant_sim::Parse;
using plant_sim::ProcessModelKindNames;
using plant_sim::ProcessModelUncertainty;

namespace {

bool FileBad(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

// j[key] of an object, or false naming the key `where` + key.
bool Member(const nlohmann::json& j, const char* key, const std::string& where, const nlohmann::json** out,
            std::string* error) {
  if (!j.is_object() || !j.contains(key)) return FileBad(error, "has no key \"" + where + key + "\"");
  *out = &j.at(key);
  return true;
}

bool Number(const nlohmann::json& j, const std::string& where, double* out, std::string* error) {
  if (!j.is_number())
    return FileBad(error, "\"" + where + "\" " + spec::Truncate(j.dump()) + " is not a number");
  const double v = j.get<double>();
  if (!std::isfinite(v) || std::abs(v) > spec::kMaxInputMagnitude)
    return FileBad(error, "\"" + where + "\" " + spec::FormatNumber(v) + " is out of range");
  *out = v;
  return true;
}

bool NumberList(const nlohmann::json& j, const std::string& where, std::vector<double>* out,
                std::string* error) {
  if (!j.is_array() || j.empty()) return FileBad(error, "\"" + where + "\" must be a list of numbers");
  out->clear();
  for (std::size_t i = 0; i < j.size(); ++i) {
    double v = 0.0;
    if (!Number(j[i], where + "[" + std::to_string(i) + "]", &v, error)) return false;
    out->push_back(v);
  }
  return true;
}

// Read with the bound checked before the bytes are (io::ReadFile); the
// message without the path, which the caller names.
bool ReadText(const std::string& path, std::string* text, std::string* error) {
  const Status s = io::ReadFile(path, kMaxModelFileBytes, text);
  if (s.ok()) return true;
  const std::string quoted = spec::Quote(path) + " ";
  const std::string& m = s.message();
  return FileBad(error, m.compare(0, quoted.size(), quoted) == 0 ? m.substr(quoted.size()) : m);
}

// A tf's "poles" and "zeros": integers in 1..kMaxTfPoles and 0..poles-1.
bool ReadTfShape(const nlohmann::json& j, ProcessModelUncertainty* m, std::string* error) {
  const nlohmann::json *poles = nullptr, *zeros = nullptr;
  if (!Member(j, "poles", "", &poles, error) || !Member(j, "zeros", "", &zeros, error)) return false;
  if (!poles->is_number_integer() || poles->get<long>() < 1 || poles->get<long>() > plant_sim::kMaxTfPoles)
    return FileBad(error, "\"poles\" " + spec::Truncate(poles->dump()) + " must be an integer in 1.." +
                              std::to_string(plant_sim::kMaxTfPoles));
  m->poles = poles->get<int>();
  if (!zeros->is_number_integer() || zeros->get<long>() < 0 || zeros->get<long>() >= m->poles)
    return FileBad(error, "\"zeros\" " + spec::Truncate(zeros->dump()) + " must be an integer in 0.." +
                              std::to_string(m->poles - 1));
  m->zeros = zeros->get<int>();
  return true;
}

// The kind and its parameter values, in the order of ParameterNames.
bool ReadParameters(const nlohmann::json& j, ProcessModelUncertainty* m, std::string* error) {
  const nlohmann::json* kind = nullptr;
  if (!Member(j, "model", "", &kind, error)) return false;
  if (!kind->is_string() || !Parse(kind->get<std::string>(), &m->kind))
    return FileBad(error,
                   "\"model\" " + spec::Truncate(kind->dump()) + " must be " + ProcessModelKindNames());
  if (m->kind == plant_sim::ProcessModelKind::kTf && !ReadTfShape(j, m, error)) return false;
  const nlohmann::json* parameters = nullptr;
  if (!Member(j, "parameters", "", &parameters, error)) return false;
  m->values.clear();
  for (const std::string& name : ParameterNames(m->kind, m->poles, m->zeros)) {
    const nlohmann::json* p = nullptr;
    const nlohmann::json* value = nullptr;
    double v = 0.0;
    if (!Member(*parameters, name.c_str(), "parameters.", &p, error) ||
        !Member(*p, "value", "parameters." + name + ".", &value, error) ||
        !Number(*value, "parameters." + name + ".value", &v, error))
      return false;
    m->values.push_back(v);
  }
  std::string why;
  if (!ParametersAreValid(m->kind, m->values, &why, m->poles, m->zeros))
    return FileBad(error, "is not a valid " + std::string(plant_sim::ToString(m->kind)) + " model: " + why);
  return true;
}

// The covariance: ok with a p x p matrix of finite numbers, or not ok (then
// no matrix is read, and the draws fall back to the coefficients).
bool ReadCovariance(const nlohmann::json& j, ProcessModelUncertainty* m, std::string* error) {
  const nlohmann::json *c = nullptr, *ok = nullptr, *matrix = nullptr;
  if (!Member(j, "covariance", "", &c, error) || !Member(*c, "ok", "covariance.", &ok, error)) return false;
  if (!ok->is_boolean()) return FileBad(error, "\"covariance.ok\" must be true or false");
  m->covariance.clear();
  if (c->contains("message") && c->at("message").is_string()) m->covariance_message = c->at("message");
  if (!ok->get<bool>()) return true;
  if (!Member(*c, "matrix", "covariance.", &matrix, error)) return false;
  const std::size_t p = m->values.size();
  std::string names;
  for (const std::string& name : ParameterNames(m->kind, m->poles, m->zeros))
    names += (names.empty() ? "" : ", ") + name;
  const std::string shape =
      "\"covariance.matrix\" must be " + std::to_string(p) + " x " + std::to_string(p) + " (" + names + ")";
  if (!matrix->is_array() || matrix->size() != p) return FileBad(error, shape);
  for (std::size_t i = 0; i < p; ++i) {
    const nlohmann::json& row = (*matrix)[i];
    if (!row.is_array() || row.size() != p) return FileBad(error, shape);
    for (std::size_t k = 0; k < p; ++k) {
      double v = 0.0;
      if (!Number(row[k], "covariance.matrix[" + std::to_string(i) + "][" + std::to_string(k) + "]", &v,
                  error))
        return false;
      m->covariance.push_back(v);
    }
  }
  for (std::size_t i = 0; i < p; ++i) {
    if (!(m->covariance[i * p + i] >= 0.0))
      return FileBad(error, "\"covariance.matrix\" has a negative variance on its diagonal");
    for (std::size_t k = 0; k < i; ++k)
      if (std::abs(m->covariance[i * p + k] - m->covariance[k * p + i]) >
          1e-9 * (std::abs(m->covariance[i * p + k]) + std::abs(m->covariance[k * p + i])))
        return FileBad(error, "\"covariance.matrix\" is not symmetric");
  }
  return true;
}

}  // namespace

bool IsModelPlant(const std::string& plant, std::string* path) {
  const std::string prefix = kModelPlantPrefix;
  if (plant.compare(0, prefix.size(), prefix) != 0) return false;
  if (path) *path = plant.substr(prefix.size());
  return true;
}

namespace {

// ReadModelFile() with the refusal's message in *error.
// The parameters' transfer function and delay against the file's (both
// scaled by their denominators' leading coefficient), to 1e-9 of the
// largest coefficient: a file whose parameters were edited, or whose
// transfer function was, is refused naming the field that disagrees.
bool ParametersGiveTheTf(const ProcessModelUncertainty& m, const Plant& file, std::string* error) {
  const plant_sim::ProcessModel model = plant_sim::ModelFromValues(m.kind, m.values, m.poles, m.zeros);
  const TransferFunction want = model.ToTransferFunction();
  const auto scaled = [](const std::vector<double>& v, double by) {
    std::vector<double> out;
    bool leading = true;
    for (double x : v) {
      if (leading && x == 0.0) continue;
      leading = false;
      out.push_back(x / by);
    }
    if (out.empty()) out.push_back(0.0);
    return out;
  };
  const auto list = [](const std::vector<double>& v) {
    std::string t = "[";
    for (std::size_t i = 0; i < v.size(); ++i) t += (i ? ", " : "") + spec::FormatNumber(v[i]);
    return t + "]";
  };
  const auto lead = [](const std::vector<double>& den) {
    for (double x : den)
      if (x != 0.0) return x;
    return 1.0;
  };
  const std::pair<const char*, std::pair<std::vector<double>, std::vector<double>>> parts[] = {
      {"num", {scaled(file.tf.num, lead(file.tf.den)), scaled(want.num, lead(want.den))}},
      {"den", {scaled(file.tf.den, lead(file.tf.den)), scaled(want.den, lead(want.den))}}};
  for (const auto& [name, pair] : parts) {
    const auto& [got, from] = pair;
    double size = 0.0;
    for (double x : from) size = std::max(size, std::fabs(x));
    bool same = got.size() == from.size();
    for (std::size_t i = 0; same && i < got.size(); ++i) same = std::fabs(got[i] - from[i]) <= 1e-9 * size;
    if (!same)
      return FileBad(error, std::string("\"transfer_function.") + name +
                                "\" disagrees with \"parameters\" (a " + plant_sim::ToString(m.kind) +
                                " model whose parameters give " + name + " " + list(from) + " against " +
                                list(got) + ", both over the denominator's leading coefficient)");
  }
  if (std::fabs(file.delay_s - model.delay_s()) > 1e-9 * std::max(1.0, model.delay_s()))
    return FileBad(error, "\"transfer_function.delay_s\" " + spec::FormatNumber(file.delay_s) +
                              " disagrees with \"parameters.Td\" " + spec::FormatNumber(model.delay_s()));
  return true;
}

bool ReadModelFileOrExplain(const std::string& path, Plant* plant, std::string* error) {
  std::string text;
  nlohmann::json j;
  std::string why;
  if (!ReadText(path, &text, error)) return false;
  if (const Status st = spec::ParseJsonText(text, &j); !st.ok()) {  // "is not valid JSON"
    *error = st.message();
    return false;
  }
  if (!j.is_object()) return FileBad(error, "is not a JSON object");
  auto m = std::make_shared<ProcessModelUncertainty>();
  if (!ReadParameters(j, m.get(), error) || !ReadCovariance(j, m.get(), error)) return false;
  const nlohmann::json *tf = nullptr, *num = nullptr, *den = nullptr, *delay = nullptr;
  Plant p;
  if (!Member(j, "transfer_function", "", &tf, error) ||
      !Member(*tf, "num", "transfer_function.", &num, error) ||
      !Member(*tf, "den", "transfer_function.", &den, error) ||
      !Member(*tf, "delay_s", "transfer_function.", &delay, error) ||
      !NumberList(*num, "transfer_function.num", &p.tf.num, error) ||
      !NumberList(*den, "transfer_function.den", &p.tf.den, error))
    return false;
  if (const Status st = MakeCustomPlant(p.tf.num, p.tf.den, &p); !st.ok())
    return FileBad(error, "is not a valid plant: " + st.message());
  if (!Number(*delay, "transfer_function.delay_s", &p.delay_s, error)) return false;
  if (p.delay_s < 0.0)
    return FileBad(error, "\"transfer_function.delay_s\" " + spec::FormatNumber(p.delay_s) + " must be >= 0");
  if (!ParametersGiveTheTf(*m, p, error)) return false;
  p.name = kModelPlantName;
  p.model = std::move(m);
  *plant = std::move(p);
  return true;
}

}  // namespace

Status ReadModelFile(const std::string& path, Plant* plant) {
  std::string why;
  if (!ReadModelFileOrExplain(path, plant, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::tune
