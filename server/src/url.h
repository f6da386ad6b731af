// The server's text helpers: a URL's path and query, percent-decoding, and
// a comparison of secrets that takes the same time for every prefix.
#pragma once

#include <string>

namespace pidlab::server::internal {

/// The value of `name` in a URL's query ("a=1&token=x"), empty if absent.
std::string QueryValue(const std::string& target, const std::string& name);
/// The target without its query.
std::string PathOf(const std::string& target);
/// "%41+b" -> "A b"; a malformed escape is kept as it is.
std::string PercentDecoded(const std::string& text);
/// Compares without an early exit, so that timing does not tell a prefix.
bool SameSecret(const std::string& a, const std::string& b);

}  // namespace pidlab::server::internal
