#pragma once
// The command line of a spec (pidlab/spec/loop_spec.h): one flag per field,
// named spec::FlagName(key), registered from the spec's field list, and the
// JSON form read by --spec FILE. Flags given on the command line override
// the file's values.

#include <CLI/CLI.hpp>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"

namespace pidlab::cli {

/// Text forms of a field's value: the default --help shows, and the value a
/// flag's text stands for (throws BadInput naming the flag).
std::string FlagText(double v);
std::string FlagText(std::uint64_t v);
std::string FlagText(int v);
std::string FlagText(bool v);
std::string FlagText(const std::string& v);
std::string FlagText(const std::vector<double>& v);
std::string FlagText(const std::pair<double, double>& v);
std::string FlagText(const std::map<std::string, double>& v);
void ParseFlag(const std::string& text, const spec::Field& f, double* v);
void ParseFlag(const std::string& text, const spec::Field& f, std::uint64_t* v);
void ParseFlag(const std::string& text, const spec::Field& f, int* v);
void ParseFlag(const std::string& text, const spec::Field& f, std::string* v);
void ParseFlag(const std::string& text, const spec::Field& f, std::vector<double>* v);
void ParseFlag(const std::string& text, const spec::Field& f, std::pair<double, double>* v);
/// One NAME=VALUE of a repeatable map flag (--stepper).
void ParseFlag(const std::string& text, const spec::Field& f, std::map<std::string, double>* v);

/// The flags of one spec on one (sub)command.
class SpecFlags {
 public:
  /// Registers a flag per field of `spec` on `app`, --help showing the
  /// values of `spec` as defaults, and (with `spec_file`) --spec FILE.
  template <typename Spec>
  void Register(CLI::App* app, Spec spec, bool spec_file = true) {
    app_ = app;
    Registrar r{this};
    spec.Serialize(&r);
    if (!spec_file) return;
    app->add_option(
        "--spec", spec_file_,
        "read the spec from this JSON file (the \"spec\" of any --json result, or a file of keys as "
        "the flags are named with '_' for '-'; docs/spec.md); flags given as well override it");
  }

  /// *spec from --spec (if given), then every flag given; their keys in
  /// *given. Throws BadInput naming the flag or the file.
  template <typename Spec>
  void Apply(Spec* spec, std::set<std::string>* given) const {
    if (!spec_file_.empty()) LoadFile(spec, given);
    Applier a{this, given};
    spec->Serialize(&a);
  }

  /// True when the flag of `key` was on the command line.
  bool Given(const std::string& key) const;

  /// `status` naming the --spec file when one was given: a rule the spec
  /// breaks (kInvalidInput) found after Apply, when the spec is built, says
  /// which file it came from ("--spec 'loop.json': horizon ...").
  Status Named(const Status& status) const;

 private:
  struct Registrar {
    SpecFlags* self;
    template <typename T>
    void Visit(const spec::Field& f, T* v) {
      self->AddOption(f, FlagText(*v), TypeName(v));
    }
    void Visit(const spec::Field& f, bool*) { self->AddFlag(f); }
    void Visit(const spec::Field& f, std::map<std::string, double>* v) { self->AddList(f, FlagText(*v)); }
  };
  struct Applier {
    const SpecFlags* self;
    std::set<std::string>* given;
    template <typename T>
    void Visit(const spec::Field& f, T* v) {
      if (!self->Given(f.key)) return;
      ParseFlag(self->text_.at(f.key), f, v);
      if (given) given->insert(f.key);
    }
    void Visit(const spec::Field& f, bool* v) {
      if (!self->Given(f.key)) return;
      *v = self->flags_.at(f.key);
      if (given) given->insert(f.key);
    }
    void Visit(const spec::Field& f, std::map<std::string, double>* v) {
      if (!self->Given(f.key)) return;
      for (const std::string& item : self->lists_.at(f.key)) ParseFlag(item, f, v);
      if (given) given->insert(f.key);
    }
  };
  static const char* TypeName(const double*) { return "FLOAT"; }
  static const char* TypeName(const std::uint64_t*) { return "UINT"; }
  static const char* TypeName(const int*) { return "INT"; }
  static const char* TypeName(const std::string*) { return "TEXT"; }
  static const char* TypeName(const std::vector<double>*) { return "A,B,..."; }
  static const char* TypeName(const std::pair<double, double>*) { return "LO,HI"; }

  void AddOption(const spec::Field& f, const std::string& default_text, const char* type_name);
  void AddFlag(const spec::Field& f);
  void AddList(const spec::Field& f, const std::string& default_text);
  template <typename Spec>
  void LoadFile(Spec* spec, std::set<std::string>* given) const {
    if (const Status st = spec::FromJson(ReadSpecFile(), spec, given); !st.ok())
      ThrowSpecFileError(st.message());
  }
  nlohmann::json ReadSpecFile() const;
  [[noreturn]] void ThrowSpecFileError(const std::string& why) const;

  CLI::App* app_ = nullptr;
  std::string spec_file_;
  // Every flag's storage, by key (std::map: references stay valid).
  std::map<std::string, std::string> text_;
  std::map<std::string, std::vector<std::string>> lists_;
  std::map<std::string, bool> flags_;
};

}  // namespace pidlab::cli
