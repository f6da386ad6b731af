#include "cli_spec.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cli_common.h"

namespace pidlab::cli {

std::string FlagText(double v) { return spec::FormatNumber(v); }
std::string FlagText(std::uint64_t v) { return std::to_string(v); }
std::string FlagText(int v) { return std::to_string(v); }
std::string FlagText(bool v) { return v ? "true" : "false"; }
std::string FlagText(const std::string& v) { return v; }
std::string FlagText(const std::vector<double>& v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? "," : "") + FlagText(v[i]);
  return out;
}
std::string FlagText(const std::pair<double, double>& v) {
  return FlagText(v.first) + "," + FlagText(v.second);
}
std::string FlagText(const std::map<std::string, double>& v) {
  std::string out;
  for (const auto& [name, x] : v) out += (out.empty() ? "" : " ") + name + "=" + FlagText(x);
  return out;
}

void ParseFlag(const std::string& text, const spec::Field& f, double* v) {
  const std::string flag = spec::FlagName(f.key);
  *v = f.Has(spec::kPercent) ? ParseSpread(text, flag) : ParseDouble(text, flag, f.Has(spec::kInfinite));
}

void ParseFlag(const std::string& text, const spec::Field& f, std::uint64_t* v) {
  const bool digits =
      !text.empty() && text.size() <= 20 && text.find_first_not_of("0123456789") == std::string::npos;
  errno = 0;
  const unsigned long long n = digits ? std::strtoull(text.c_str(), nullptr, 10) : 0;
  if (!digits || errno == ERANGE)
    throw BadInput(spec::FlagName(f.key) + " " + Quote(text) +
                   " must be a whole number from 0 to 18446744073709551615");
  *v = n;
}

void ParseFlag(const std::string& text, const spec::Field& f, int* v) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const long n = std::strtol(begin, &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || n < -2147483647L - 1 || n > 2147483647L)
    throw BadInput(spec::FlagName(f.key) + " " + Quote(text) + " must be a whole number");
  *v = static_cast<int>(n);
}

void ParseFlag(const std::string& text, const spec::Field&, std::string* v) { *v = text; }

void ParseFlag(const std::string& text, const spec::Field& f, std::vector<double>* v) {
  *v = ParseList(text, spec::FlagName(f.key), f.Has(spec::kInfinite));
}

void ParseFlag(const std::string& text, const spec::Field& f, std::pair<double, double>* v) {
  const std::string flag = spec::FlagName(f.key);
  const std::vector<double> lo_hi = ParseList(text, flag, f.Has(spec::kInfinite));
  if (lo_hi.size() != 2) throw BadInput(flag + " " + Quote(text) + " must be LO,HI");
  *v = {lo_hi[0], lo_hi[1]};
}

void ParseFlag(const std::string& text, const spec::Field& f, std::map<std::string, double>* v) {
  const std::string flag = spec::FlagName(f.key);
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw BadInput(flag + " " + Quote(text) + " must be NAME=VALUE");
  const std::string name = text.substr(0, eq);
  (*v)[name] = ParseDouble(text.substr(eq + 1), flag + " " + Truncate(name));
}

namespace {

std::string HelpOf(const spec::Field& f) {
  std::string help = f.help;
  if (*f.unit) help += " [" + std::string(f.unit) + "]";
  return help;
}

}  // namespace

void SpecFlags::AddOption(const spec::Field& f, const std::string& default_text, const char* type_name) {
  CLI::Option* o = app_->add_option(spec::FlagName(f.key), text_[f.key], HelpOf(f))->type_name(type_name);
  if (!default_text.empty()) o->default_str(default_text);
}

void SpecFlags::AddFlag(const spec::Field& f) {
  app_->add_flag(spec::FlagName(f.key), flags_[f.key], HelpOf(f));
}

void SpecFlags::AddList(const spec::Field& f, const std::string& default_text) {
  CLI::Option* o = app_->add_option(spec::FlagName(f.key), lists_[f.key], HelpOf(f))->take_all();
  if (!default_text.empty()) o->default_str(default_text);
}

bool SpecFlags::Given(const std::string& key) const { return app_->count(spec::FlagName(key)) > 0; }

nlohmann::json SpecFlags::ReadSpecFile() const {
  std::string text;
  if (Status s = io::ReadFile(spec_file_, kMaxSpecFileBytes, &text); !s.ok())
    Require(Status(s.code(), "--spec " + s.message()));
  nlohmann::json j;
  if (const Status st = spec::ParseJsonText(text, &j); !st.ok()) ThrowSpecFileError(st.message());
  // A --json result: its "spec".
  if (j.is_object() && j.contains("spec") && j["spec"].is_object()) j = nlohmann::json(j["spec"]);
  // A plant named on the command line (--plant, --model, --num/--den)
  // replaces the file's plant, whichever form either was given in: the
  // file's plant, model, num and den are dropped (its delay and stepper
  // options stay, and are checked against the new plant).
  const char* const kPlantKeys[] = {"plant", "model", "num", "den"};
  bool plant_given = false;
  for (const char* key : kPlantKeys) plant_given = plant_given || Given(key);
  if (plant_given && j.is_object())
    for (const char* key : kPlantKeys) j.erase(key);
  return j;
}

Status SpecFlags::Named(const Status& status) const {
  if (status.ok() || spec_file_.empty() || status.code() != StatusCode::kInvalidInput) return status;
  const std::string prefix = "--spec " + Quote(spec_file_) + ": ";
  if (status.message().rfind(prefix, 0) == 0) return status;
  return Status(status.code(), prefix + status.message());
}

void SpecFlags::ThrowSpecFileError(const std::string& why) const {
  throw BadInput("--spec " + Quote(spec_file_) + ": " + why);
}

}  // namespace pidlab::cli
