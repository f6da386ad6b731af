// The server's text helpers: a URL's path and query, percent-decoding, a
// comparison of secrets that takes the same time for every prefix, and the
// JSON library's words for a request's mistake.
#pragma once

#include <string>
#include <utility>

#include "pidlab/server/server.h"

namespace pidlab::server::internal {

/// Why a request to the server bound by `options` on `port` may not be
/// served, as an HTTP status and a line (200 and "" when it may): its token
/// (`?token=` in `target`, or `authorization` "Bearer ..."), its Host, and
/// its Origin if it has one (401, 403).
std::pair<int, std::string> Refusal(const ServerOptions& options, int port, const std::string& target,
                                    const std::string& authorization, const std::string& host,
                                    const std::string* origin);

/// The value of `name` in a URL's query ("a=1&token=x"), empty if absent.
std::string QueryValue(const std::string& target, const std::string& name);
/// The target without its query.
std::string PathOf(const std::string& target);
/// "%41+b" -> "A b"; a malformed escape is kept as it is.
std::string PercentDecoded(const std::string& text);
/// Compares without an early exit, so that timing does not tell a prefix.
bool SameSecret(const std::string& a, const std::string& b);
/// An exception's text without the JSON library's "[json.exception.type_error.302] ".
std::string JsonLibraryWords(const std::string& what);

}  // namespace pidlab::server::internal
