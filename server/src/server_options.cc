// ServerOptions::IsValid, IsLoopback, the request checks and text helpers of
// url.h, and the Server constructor for a plain Handler.

#include <boost/asio/ip/address.hpp>
#include <cctype>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "pidlab/server/server.h"
#include "pidlab/spec/field.h"
#include "url.h"

namespace pidlab::server {

namespace internal {

std::string QueryValue(const std::string& target, const std::string& name) {
  const std::size_t q = target.find('?');
  if (q == std::string::npos) return "";
  std::istringstream in(target.substr(q + 1));
  std::string pair;
  while (std::getline(in, pair, '&'))
    if (pair.compare(0, name.size() + 1, name + "=") == 0) return pair.substr(name.size() + 1);
  return "";
}

std::string PathOf(const std::string& target) { return target.substr(0, target.find('?')); }

std::string PercentDecoded(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] == '%' && i + 2 < text.size() &&
               std::isxdigit(static_cast<unsigned char>(text[i + 1])) &&
               std::isxdigit(static_cast<unsigned char>(text[i + 2]))) {
      out += static_cast<char>(std::stoi(text.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

bool SameSecret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::pair<int, std::string> Refusal(const ServerOptions& options, int port, const std::string& target,
                                    const std::string& authorization, const std::string& host,
                                    const std::string* origin) {
  if (!options.token.empty()) {
    std::string given = QueryValue(target, "token");
    if (given.empty() && authorization.rfind("Bearer ", 0) == 0) given = authorization.substr(7);
    if (!SameSecret(given, options.token)) return {401, "a valid token is required"};
  }
  const std::string suffix = ":" + std::to_string(port);
  std::set<std::string> hosts = {"127.0.0.1" + suffix, "localhost" + suffix, "[::1]" + suffix};
  hosts.insert((options.bind.find(':') != std::string::npos ? "[" + options.bind + "]" : options.bind) +
               suffix);
  // Bound to every address: any Host, as the token guards it.
  const bool any = options.bind == "0.0.0.0" || options.bind == "::";
  if (!any && hosts.count(host) == 0) return {403, "Host '" + host + "' is not this server"};
  if (origin && *origin != "http://" + host) return {403, "Origin '" + *origin + "' is not this server's"};
  return {200, ""};
}

std::string JsonLibraryWords(const std::string& what) {
  const std::size_t end = what.find("] ");
  return what.rfind("[json.exception.", 0) == 0 && end != std::string::npos ? what.substr(end + 2) : what;
}

}  // namespace internal

bool IsLoopback(const std::string& address) {
  boost::system::error_code ec;
  const boost::asio::ip::address a = boost::asio::ip::make_address(address, ec);
  return !ec && a.is_loopback();
}

bool ServerOptions::IsValid(std::string* error) const {
  std::string e;
  boost::system::error_code ec;
  boost::asio::ip::make_address(bind, ec);
  if (ec)
    e = "bind address '" + bind + "' is not an IPv4 or IPv6 address";
  else if (port < 0 || port > 65535)
    e = "port " + std::to_string(port) + " must be in 0..65535";
  else if (!IsLoopback(bind) && token.size() < 16)
    e = "bind address '" + bind + "' is not loopback: a token of at least 16 characters is required";
  else if (max_body_bytes < 1024 || max_message_bytes < 1024 || max_header_bytes < 1024 ||
           max_upload_bytes < 1024)
    e = "the size limits must be at least 1024 bytes";
  else if (max_connections < 1)
    e = "max_connections " + std::to_string(max_connections) + " must be at least 1";
  else if (max_connections_per_address < 1 || max_connections_per_address > max_connections)
    e = "max_connections_per_address " + std::to_string(max_connections_per_address) + " must be in 1.." +
        std::to_string(max_connections);
  else if (!(header_timeout_s >= 0.1 && header_timeout_s <= 600))
    e = "header_timeout_s " + std::to_string(header_timeout_s) + " must be in 0.1..600";
  else if (!(body_timeout_s >= 0.1 && body_timeout_s <= 3600))
    e = "body_timeout_s " + spec::FormatNumber(body_timeout_s) + " must be in 0.1..3600";
  else if (!(websocket_idle_timeout_s >= 0.1 && websocket_idle_timeout_s <= 3600))
    e = "websocket_idle_timeout_s " + std::to_string(websocket_idle_timeout_s) + " must be in 0.1..3600";
  else if (max_bodies_bytes < 1024)
    e = "max_bodies_bytes " + std::to_string(max_bodies_bytes) + " must be at least 1024";
  if (error) *error = e;
  return e.empty();
}

// The plain handler's constructor: the connection handler's, without the connection.
Server::Server(ServerOptions options, Handler handler, std::vector<Asset> assets)
    : Server(std::move(options),
             ConnectionHandler([handler = std::move(handler)](const nlohmann::json& request,
                                                              const std::shared_ptr<Connection>&) {
               return handler(request);
             }),
             std::move(assets)) {}

}  // namespace pidlab::server
