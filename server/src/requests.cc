// What the server answers (impl.h): an HTTP request (an asset, /api/health,
// /api/request, /api/upload) and a request object of /api/request or the
// WebSocket, through the handler.

#include <boost/beast/http.hpp>
#include <exception>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "impl.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/status.h"
#include "url.h"

namespace pidlab::server {
namespace http = boost::beast::http;
using internal::JsonLibraryWords;
using internal::JsonResponse;
using internal::PathOf;
using internal::PercentDecoded;
using internal::QueryValue;
using internal::Request;
using internal::Response;

namespace internal {

bool IsUpload(const Request& req) {
  return req.method() == http::verb::post && PathOf(std::string(req.target())) == "/api/upload";
}

Response JsonResponse(const Request& req, http::status status, const nlohmann::json& body) {
  Response res{status, req.version()};
  res.set(http::field::content_type, "application/json");
  res.set(http::field::cache_control, "no-store");
  res.keep_alive(req.keep_alive() && status != http::status::bad_request);
  res.body() = body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  res.prepare_payload();
  return res;
}

}  // namespace internal

bool Server::Impl::MakeRoom(const std::string& address) {
  int evicted = 0;
  const bool room =
      slots.MakeRoom(address, options.max_connections_per_address, options.max_connections, &evicted);
  for (; evicted > 0; --evicted) Count(&ServerCounters::evicted);
  return room;
}

std::pair<http::status, std::string> Server::Impl::Refusal(const Request& req) const {
  const auto origin = req.find(http::field::origin);
  const std::string origin_text = origin == req.end() ? "" : std::string(origin->value());
  const auto [status, why] = internal::Refusal(
      options, port, std::string(req.target()), std::string(req[http::field::authorization]),
      std::string(req[http::field::host]), origin == req.end() ? nullptr : &origin_text);
  return {static_cast<http::status>(status), why};
}

Reply Server::Impl::Answer(const std::string& text, const std::shared_ptr<Connection>& connection) {
  // The one JSON reader of every file and request: nesting beyond
  // spec::kMaxJsonDepth is refused before any parser runs.
  if (const Status st = spec::CheckJsonNesting(text, spec::kMaxJsonDepth); !st.ok()) {
    Count(&ServerCounters::malformed);
    return {400, {{"error", "the request's JSON " + st.message()}}};
  }
  nlohmann::json request;
  if (!spec::ParseJsonText(text, &request).ok() || !request.is_object()) {
    Count(&ServerCounters::malformed);
    return {400, {{"error", "a request must be one JSON object"}}};
  }
  Reply reply;
  try {
    reply = handler(request, connection);
  } catch (const nlohmann::json::exception& e) {
    // A field of the wrong JSON type ({"type": 5}): the request's mistake.
    Count(&ServerCounters::malformed);
    reply = {400, {{"error", "the request is not of the expected form: " + JsonLibraryWords(e.what())}}};
  } catch (const std::exception& e) {
    reply = {500, {{"error", std::string("the server failed: ") + e.what()}}};
  }
  if (request.contains("id") && reply.body.is_object()) reply.body["id"] = request["id"];
  return reply;
}

Response Server::Impl::Upload(const Request& req) {
  Reply r;
  try {
    r = upload_handler(PercentDecoded(QueryValue(std::string(req.target()), "name")), req.body());
  } catch (const std::exception& e) {
    r = {500, {{"error", std::string("the server failed: ") + e.what()}}};
  }
  if (r.status == 400) Count(&ServerCounters::malformed);
  return JsonResponse(req, static_cast<http::status>(r.status), r.body);
}

Response Server::Impl::Serve(const Request& req) {
  Count(&ServerCounters::http_requests);
  const auto [status, why] = Refusal(req);
  if (status != http::status::ok) {
    Count(&ServerCounters::refused);
    return JsonResponse(req, status, {{"error", why}});
  }
  const std::string path = PathOf(std::string(req.target()));
  if (req.method() == http::verb::get) {
    for (const Asset& a : assets)
      if (a.path == path) {
        Response res{http::status::ok, req.version()};
        res.set(http::field::content_type, a.content_type);
        res.set("X-Content-Type-Options", "nosniff");
        res.set("Content-Security-Policy", "default-src 'self'; connect-src 'self'");
        res.keep_alive(req.keep_alive());
        res.body() = a.body;
        res.prepare_payload();
        return res;
      }
    if (path == "/api/health") return JsonResponse(req, http::status::ok, {{"ok", true}});
    return JsonResponse(req, http::status::not_found, {{"error", "no such path: " + path}});
  }
  if (req.method() == http::verb::post && path == "/api/request") {
    const Reply r = Answer(req.body());
    return JsonResponse(req, static_cast<http::status>(r.status), r.body);
  }
  if (internal::IsUpload(req) && upload_handler) return Upload(req);
  return JsonResponse(req, http::status::method_not_allowed, {{"error", "method or path not served"}});
}

}  // namespace pidlab::server
