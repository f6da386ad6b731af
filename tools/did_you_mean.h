#pragma once
// "did you mean --plant?": the closest valid name to a mistyped subcommand
// or option.

#include <string>
#include <vector>

namespace pidlab::cli {

/// The optimal-string-alignment distance: the fewest insertions, deletions,
/// substitutions and swaps of two adjacent characters that turn `a` into `b`
/// ("plnat" -> "plant" is 1).
std::size_t EditDistance(const std::string& a, const std::string& b);

/// The name of `names` closest to `typed` by EditDistance, the first of
/// equals; "" when none is close. With n the characters of `typed` after its
/// leading dashes, a name is close when at most 1 + n / 4 edits away and fewer
/// than n ("x" and "--x" suggest nothing). Pass options as typed, dashes
/// included ("--plnat" against "--plant", "-v").
std::string ClosestName(const std::string& typed, const std::vector<std::string>& names);

}  // namespace pidlab::cli
