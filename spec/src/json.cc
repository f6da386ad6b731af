#include "pidlab/spec/json.h"

#include <cmath>

#include "pidlab/spec/loop_spec.h"

namespace pidlab::spec {
namespace {

bool Fail(const Field& f, const std::string& expected, const nlohmann::json& got, std::string* error) {
  if (error) {
    // A long string is cut before it is printed; the rest is at most
    // kMaxJsonDepth deep (ParseJsonText), so printing it is bounded.
    std::string text = got.is_string() ? nlohmann::json(Truncate(got.get<std::string>(), 60))
                                             .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
                                       : got.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() > 60) text = text.substr(0, 57) + "...";
    *error = "spec key '" + std::string(f.key) + "' must be " + expected + ", not " + text;
  }
  return false;
}

// A number, or "inf" / "-inf" where the field allows infinity.
bool Number(const nlohmann::json& j, const Field& f, double* v, std::string* error) {
  if (j.is_number()) {
    *v = j.get<double>();
    return true;
  }
  if (j.is_string() && f.Has(kInfinite)) {
    const std::string s = j.get<std::string>();
    if (s == "inf" || s == "+inf") *v = kInf;
    if (s == "-inf") *v = -kInf;
    if (s == "inf" || s == "+inf" || s == "-inf") return true;
  }
  return Fail(f, f.Has(kInfinite) ? "a number, \"inf\" or \"-inf\"" : "a number", j, error);
}

}  // namespace

int kSpecVersionForJson() { return kSpecVersion; }

namespace internal {

bool CheckVersion(const nlohmann::json& j, std::string* error) {
  const auto it = j.find("version");
  if (it == j.end() || (it->is_number_integer() && it->get<long long>() == kSpecVersion)) return true;
  if (error)
    *error = "spec version " +
             Truncate(it->dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), 60) + " is not " +
             std::to_string(kSpecVersion) + ", the one this pidlab reads";
  return false;
}

}  // namespace internal

Status CheckJsonNesting(const std::string& text, int max_depth) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;  // the escaped character, whatever it is
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        return Status::InvalidInput("is nested deeper than " + std::to_string(max_depth) +
                                    " levels (at byte " + std::to_string(i) + ")");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return Status::Ok();
}

Status ParseJsonText(const std::string& text, nlohmann::json* out) {
  // Checked before parsing: nlohmann's parser is iterative, but copying,
  // comparing and printing a value recurse once per level.
  if (Status st = CheckJsonNesting(text, kMaxJsonDepth); !st.ok()) return st;
  *out = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (out->is_discarded()) {
    return Status::InvalidInput("is not valid JSON");
  }
  return Status::Ok();
}

nlohmann::json ToJsonValue(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}
nlohmann::json ToJsonValue(std::uint64_t v) { return v; }
nlohmann::json ToJsonValue(int v) { return v; }
nlohmann::json ToJsonValue(bool v) { return v; }
nlohmann::json ToJsonValue(const std::string& v) { return v; }
nlohmann::json ToJsonValue(const std::vector<double>& v) {
  nlohmann::json j = nlohmann::json::array();
  for (double x : v) j.push_back(ToJsonValue(x));
  return j;
}
nlohmann::json ToJsonValue(const std::pair<double, double>& v) {
  return nlohmann::json::array({ToJsonValue(v.first), ToJsonValue(v.second)});
}
nlohmann::json ToJsonValue(const std::map<std::string, double>& v) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, x] : v) j[name] = ToJsonValue(x);
  return j;
}

namespace internal {

bool FromJsonValue(const nlohmann::json& j, const Field& f, double* v, std::string* error) {
  return Number(j, f, v, error);
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, std::uint64_t* v, std::string* error) {
  if (!j.is_number_unsigned()) return Fail(f, "a whole number from 0 to 18446744073709551615", j, error);
  *v = j.get<std::uint64_t>();
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, int* v, std::string* error) {
  if (!j.is_number_integer() || j.get<long long>() < -2147483648LL || j.get<long long>() > 2147483647LL)
    return Fail(f, "a whole number", j, error);
  *v = j.get<int>();
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, bool* v, std::string* error) {
  if (!j.is_boolean()) return Fail(f, "true or false", j, error);
  *v = j.get<bool>();
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, std::string* v, std::string* error) {
  if (!j.is_string()) return Fail(f, "a string", j, error);
  *v = j.get<std::string>();
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, std::vector<double>* v, std::string* error) {
  if (!j.is_array()) return Fail(f, "an array of numbers", j, error);
  std::vector<double> out;
  for (const auto& x : j) {
    double d = 0;
    if (!Number(x, f, &d, error)) return false;
    out.push_back(d);
  }
  *v = std::move(out);
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, std::pair<double, double>* v,
                   std::string* error) {
  if (!j.is_array() || j.size() != 2) return Fail(f, "an array [LO, HI]", j, error);
  std::pair<double, double> out;
  if (!Number(j[0], f, &out.first, error) || !Number(j[1], f, &out.second, error)) return false;
  *v = out;
  return true;
}

bool FromJsonValue(const nlohmann::json& j, const Field& f, std::map<std::string, double>* v,
                   std::string* error) {
  if (!j.is_object()) return Fail(f, "an object {NAME: VALUE}", j, error);
  std::map<std::string, double> out;
  for (const auto& item : j.items()) {
    double d = 0;
    if (!Number(item.value(), f, &d, error)) return false;
    out[item.key()] = d;
  }
  *v = std::move(out);
  return true;
}

}  // namespace internal

}  // namespace pidlab::spec
