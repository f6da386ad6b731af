#pragma once
// One field of a spec (loop_spec.h): its key, help, unit and what it may
// hold. A spec lists its fields once, in Serialize(Archive*), in the manner of
// Drake's DRAKE_NVP: every reader and writer (the CLI flags, the Python
// keywords, the JSON form, the field table of the tests) is an archive that
// visits that one list. A new field is one line there.

#include <cstddef>
#include <string>

namespace pidlab::spec {

/// What a field may hold beyond its C++ type.
enum FieldFlag : unsigned {
  kNone = 0,
  /// Travels to the process trio in the episode configuration (and so into
  /// logs and replay); checked by the field-table test.
  kEpisode = 1u << 0,
  /// A number that may also be +inf or -inf ("none": --max-ms inf).
  kInfinite = 1u << 1,
  /// A relative spread typed as "10%" or 0.1 (the JSON holds the number).
  kPercent = 1u << 2,
  /// Given to `tune`, it asks for a search over the box (an objective, a
  /// box, a budget, a step or robustness bound, the robust preset or set),
  /// not migo's design (docs/tuning.md, "Any plant").
  kSearch = 1u << 3,
};

struct Field {
  /// The JSON key and the Python keyword; the CLI flag is "--" + key with
  /// '_' written '-' (FlagName).
  const char* key;
  /// One line of help (--help, the Python docstring, the field table).
  const char* help;
  /// Unit of a number ("s", "N m", ...), "" where it has none.
  const char* unit = "";
  unsigned flags = kNone;
  /// A valid value other than the default, as JSON text: the field-table
  /// test sets it through every front end and checks that it arrives.
  const char* example = "";

  bool Has(FieldFlag f) const { return (flags & f) != 0; }
};

/// "--" + key with '_' written '-': "sample_time" -> "--sample-time".
std::string FlagName(const std::string& key);

/// How a validation message names a field: by its key (Python, JSON) or by
/// its flag (the command line).
enum class NameStyle { kKey, kFlag };
/// `key` as `style` names it.
std::string DisplayName(const std::string& key, NameStyle style);

/// The most characters of a user's value a message echoes.
inline constexpr std::size_t kMaxEchoedChars = 120;
/// Every number a user gives is finite (unless the field takes infinity) and
/// at most this in magnitude (README.md, "Exit status and limits").
inline constexpr double kMaxInputMagnitude = 1e12;
/// `text` made printable on one line (control characters escaped as \n,
/// \xHH) and cut to at most `max_chars`, the cut marked "...(N chars)".
std::string Truncate(const std::string& text, std::size_t max_chars = kMaxEchoedChars);
/// "'" + Truncate(text) + "'": how every message quotes a user's value.
std::string Quote(const std::string& text);
/// A number as a message shows it (%g; inf, nan).
std::string FormatNumber(double v);

}  // namespace pidlab::spec
