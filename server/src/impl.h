#pragma once
// The server's state that its connections share (server.cc) and the answers
// to its requests (requests.cc): the options, the handlers, the budget of
// slots and bodies, and the counters. Touched on the server's thread, but
// for the counters.

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http.hpp>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "pidlab/server/server.h"
#include "slots.h"

namespace pidlab::server {
namespace internal {

using Request = boost::beast::http::request<boost::beast::http::string_body>;
using Response = boost::beast::http::response<boost::beast::http::string_body>;

/// `body` as the JSON response to `req` (no-store; the connection kept alive
/// as the request asks, but after a 400).
Response JsonResponse(const Request& req, boost::beast::http::status status, const nlohmann::json& body);

/// Whether `req` is POST /api/upload.
bool IsUpload(const Request& req);

}  // namespace internal

struct Server::Impl : std::enable_shared_from_this<Server::Impl> {
  // Every connection and body held in memory: one budget (slots.h).
  using Slots = internal::Slots;

  ServerOptions options;
  ConnectionHandler handler;
  UploadHandler upload_handler;
  std::vector<Asset> assets;
  boost::asio::io_context io{1};
  boost::asio::ip::tcp::acceptor acceptor{io};
  int port = 0;
  Slots slots;
  mutable std::mutex counters_mutex;
  ServerCounters counters;

  void Count(long ServerCounters::*field) {
    std::lock_guard<std::mutex> lock(counters_mutex);
    ++(counters.*field);
  }

  // Whether a new connection from `address` may open (slots.h: the
  // connections idle longest closed for it where a cap is reached).
  bool MakeRoom(const std::string& address);

  // The upload bodies held in memory at once, every connection's together
  // (other bodies are at most max_body_bytes on each of max_connections).
  std::size_t BodyBudget() const { return std::max(options.max_bodies_bytes, options.max_upload_bytes); }

  // Why `req` may not be served (token, host, origin), or 200 and "" (url.h).
  std::pair<boost::beast::http::status, std::string> Refusal(const internal::Request& req) const;

  // One request object through the handler: the reply's status and body
  // (400 for JSON that is not one object or nests too deep, or a field of
  // the wrong JSON type; 500 for the handler's exception).
  Reply Answer(const std::string& text, const std::shared_ptr<Connection>& connection = nullptr);

  // The answer to a whole HTTP request: an asset, /api/health, /api/request
  // or /api/upload.
  internal::Response Serve(const internal::Request& req);

 private:
  internal::Response Upload(const internal::Request& req);
};

}  // namespace pidlab::server
