#pragma once
// The JSON form of a spec: one object whose keys are the fields' keys (the
// Python keywords), plus "version". Numbers that may be infinite are written
// "inf" / "-inf" (JSON has no infinity), every double with 17 significant
// digits, so a spec read back is the spec written, bit for bit.
//   pidlab evaluate --spec FILE, pidlab tune --spec FILE, and the "spec" key
//   of every --json result.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/spec/field.h"
#include "pidlab/spec/status.h"

namespace pidlab::spec {

// One value to JSON.
nlohmann::json ToJsonValue(double v);
nlohmann::json ToJsonValue(std::uint64_t v);
nlohmann::json ToJsonValue(int v);
nlohmann::json ToJsonValue(bool v);
nlohmann::json ToJsonValue(const std::string& v);
nlohmann::json ToJsonValue(const std::vector<double>& v);
nlohmann::json ToJsonValue(const std::pair<double, double>& v);
nlohmann::json ToJsonValue(const std::map<std::string, double>& v);
// The reader's pieces, for JsonReader and FromJson below (templates, so in
// this header); callers use FromJson. From*: false with *error naming `key`
// and what was expected.
namespace internal {
bool FromJsonValue(const nlohmann::json& j, const Field& f, double* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, std::uint64_t* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, int* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, bool* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, std::string* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, std::vector<double>* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, std::pair<double, double>* v, std::string* error);
bool FromJsonValue(const nlohmann::json& j, const Field& f, std::map<std::string, double>* v,
                   std::string* error);
/// True if "version" is absent or kSpecVersion; else false with *error.
bool CheckVersion(const nlohmann::json& j, std::string* error);
}  // namespace internal

/// kSpecVersion (loop_spec.h), for ToJson.
int kSpecVersionForJson();
/// The deepest nesting of arrays and objects any JSON pidlab reads may have
/// (a spec, a model file, a result, a request to the server).
inline constexpr int kMaxJsonDepth = 64;
/// A failed Status (kInvalidInput: "is nested deeper than 64 levels (at byte
/// N)") if `text` opens more than `max_depth` arrays or objects at once;
/// strings are skipped. One pass, no recursion, before any parser runs.
Status CheckJsonNesting(const std::string& text, int max_depth);
/// The one JSON reader of every file and request: the nesting checked
/// (kMaxJsonDepth), then parsed; a failed Status (kInvalidInput: "is not
/// valid JSON") otherwise.
Status ParseJsonText(const std::string& text, nlohmann::json* out);

/// Writes every field (Archive for Serialize).
class JsonWriter {
 public:
  explicit JsonWriter(nlohmann::json* out) : out_(out) {}
  template <typename T>
  void Visit(const Field& f, T* v) {
    (*out_)[f.key] = ToJsonValue(*v);
  }

 private:
  nlohmann::json* out_;
};

/// Reads the fields present in an object, records their keys in *given, and
/// keeps the first error.
class JsonReader {
 public:
  JsonReader(const nlohmann::json& in, std::set<std::string>* given) : in_(in), given_(given) {}
  template <typename T>
  void Visit(const Field& f, T* v) {
    known_.insert(f.key);
    const auto it = in_.find(f.key);
    if (it == in_.end() || !error_.empty()) return;
    if (internal::FromJsonValue(*it, f, v, &error_) && given_) given_->insert(f.key);
  }
  const std::set<std::string>& known() const { return known_; }
  const std::string& error() const { return error_; }

 private:
  const nlohmann::json& in_;
  std::set<std::string>* given_;
  std::set<std::string> known_;
  std::string error_;
};

/// The field table: every field with its default value (Archive for Serialize).
struct FieldEntry {
  Field field;
  nlohmann::json default_value;
};
class FieldLister {
 public:
  template <typename T>
  void Visit(const Field& f, T* v) {
    entries.push_back({f, ToJsonValue(*v)});
  }
  std::vector<FieldEntry> entries;
};

/// The JSON form of `spec`, with "version".
template <typename Spec>
nlohmann::json ToJson(Spec spec) {
  nlohmann::json j = nlohmann::json::object();
  j["version"] = kSpecVersionForJson();
  JsonWriter w(&j);
  spec.Serialize(&w);
  return j;
}

/// Reads `j` over *spec (fields absent keep their value). A failed Status
/// (kInvalidInput) for a key no field has, a value of the wrong type, or
/// another version. *given (may be null) gets the keys present.
template <typename Spec>
Status FromJson(const nlohmann::json& j, Spec* spec, std::set<std::string>* given) {
  if (!j.is_object())
    return Status::InvalidInput("a spec must be a JSON object, not " + std::string(j.type_name()));
  std::string error;
  if (!internal::CheckVersion(j, &error)) return Status::InvalidInput(error);
  JsonReader r(j, given);
  spec->Serialize(&r);
  if (!r.error().empty()) return Status::InvalidInput(r.error());
  for (const auto& item : j.items())
    if (item.key() != "version" && r.known().count(item.key()) == 0)
      return Status::InvalidInput("spec key " + Quote(item.key()) + " is unknown");
  return Status::Ok();
}

/// The fields of `Spec` with the defaults of `spec`.
template <typename Spec>
std::vector<FieldEntry> Fields(Spec spec = Spec{}) {
  FieldLister l;
  spec.Serialize(&l);
  return l.entries;
}

}  // namespace pidlab::spec
