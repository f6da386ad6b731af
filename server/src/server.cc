#include "pidlab/server/server.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

#include "pidlab/spec/json.h"
#include "slots.h"
#include "url.h"

namespace pidlab::server {
namespace {
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;
using internal::JsonLibraryWords;
using internal::PathOf;
using internal::PercentDecoded;
using internal::QueryValue;

bool IsUpload(const Request& req) {
  return req.method() == http::verb::post && PathOf(std::string(req.target())) == "/api/upload";
}

// A request's body after its header: the time it may take.
constexpr std::chrono::seconds kBodyTimeout{30};

// WebSocket replies waiting beyond this many bytes: the session stops reading
// requests until they are written (a client that sends and never reads).
constexpr std::size_t kMaxQueuedReplyBytes = 1 << 20;

Response JsonResponse(const Request& req, http::status status, const nlohmann::json& body) {
  Response res{status, req.version()};
  res.set(http::field::content_type, "application/json");
  res.set(http::field::cache_control, "no-store");
  res.keep_alive(req.keep_alive() && status != http::status::bad_request);
  res.body() = body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  res.prepare_payload();
  return res;
}

}  // namespace

struct Server::Impl : std::enable_shared_from_this<Server::Impl> {
  // Every connection and body held in memory: one budget (slots.h).
  using Slots = internal::Slots;

  ServerOptions options;
  ConnectionHandler handler;
  UploadHandler upload_handler;
  std::vector<Asset> assets;
  net::io_context io{1};
  tcp::acceptor acceptor{io};
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
  bool MakeRoom(const std::string& address) {
    int evicted = 0;
    const bool room =
        slots.MakeRoom(address, options.max_connections_per_address, options.max_connections, &evicted);
    for (; evicted > 0; --evicted) Count(&ServerCounters::evicted);
    return room;
  }

  // The upload bodies held in memory at once, every connection's together
  // (other bodies are at most max_body_bytes on each of max_connections).
  std::size_t BodyBudget() const { return std::max(options.max_bodies_bytes, options.max_upload_bytes); }

  // Why `req` may not be served (token, host, origin), or empty (url.h).
  std::pair<http::status, std::string> Refusal(const Request& req) const {
    const auto origin = req.find(http::field::origin);
    const std::string origin_text = origin == req.end() ? "" : std::string(origin->value());
    const auto [status, why] = internal::Refusal(
        options, port, std::string(req.target()), std::string(req[http::field::authorization]),
        std::string(req[http::field::host]), origin == req.end() ? nullptr : &origin_text);
    return {static_cast<http::status>(status), why};
  }

  // One request object through the handler: the reply's status and body.
  Reply Answer(const std::string& text, const std::shared_ptr<Connection>& connection = nullptr) {
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

  Response Upload(const Request& req) {
    Reply r;
    try {
      r = upload_handler(PercentDecoded(QueryValue(std::string(req.target()), "name")), req.body());
    } catch (const std::exception& e) {
      r = {500, {{"error", std::string("the server failed: ") + e.what()}}};
    }
    if (r.status == 400) Count(&ServerCounters::malformed);
    return JsonResponse(req, static_cast<http::status>(r.status), r.body);
  }

  Response Serve(const Request& req) {
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
    if (IsUpload(req) && upload_handler) return Upload(req);
    return JsonResponse(req, http::status::method_not_allowed, {{"error", "method or path not served"}});
  }
};

namespace {

class WebSocketSession;

// The handler's view of a session: posts onto the session's executor.
class SessionConnection : public Connection {
 public:
  SessionConnection(net::any_io_executor executor, std::weak_ptr<WebSocketSession> session)
      : executor_(std::move(executor)), session_(std::move(session)) {}
  bool Post(const nlohmann::json& message, const std::string& replace_key) override;
  bool PostBinary(std::string bytes, const std::string& replace_key) override;
  bool closed() const override { return closed_; }
  void Close() { closed_ = true; }
  void CountDropped() { ++dropped_; }

 private:
  net::any_io_executor executor_;
  std::weak_ptr<WebSocketSession> session_;
  std::atomic<bool> closed_{false};
};

class WebSocketSession : public std::enable_shared_from_this<WebSocketSession> {
 public:
  // Takes over the HTTP session's socket and its slot.
  WebSocketSession(tcp::socket&& socket, std::shared_ptr<Server::Impl> server, Server::Impl::Slots::Id slot)
      : ws_(std::move(socket)), server_(std::move(server)), slot_(slot) {}
  ~WebSocketSession() {
    if (connection_) connection_->Close();
    server_->slots.Close(slot_);
  }

  void Run(Request req) {
    connection_ = std::make_shared<SessionConnection>(ws_.get_executor(), weak_from_this());
    // Pinged after half the idle timeout without a byte from the client,
    // closed at the whole: a page answers pings, a dead peer does not.
    auto timeout = websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeout.idle_timeout = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(server_->options.websocket_idle_timeout_s));
    timeout.keep_alive_pings = true;
    ws_.set_option(timeout);
    ws_.read_message_max(server_->options.max_message_bytes);
    // Closed for a new connection when it is the one idle longest, and when the server stops.
    const auto close = [weak = weak_from_this()] {
      if (auto self = weak.lock()) self->Evict();
    };
    server_->slots.Idle(slot_, close);
    server_->slots.OnStop(slot_, close);
    ws_.async_accept(req, beast::bind_front_handler(&WebSocketSession::OnAccept, shared_from_this()));
  }

 private:
  void OnAccept(beast::error_code ec) {
    if (!ec) Read();
  }
  void Evict() {
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }
  void Read() {
    ws_.async_read(buffer_, beast::bind_front_handler(&WebSocketSession::OnRead, shared_from_this()));
  }
  void OnRead(beast::error_code ec, std::size_t) {
    if (ec) {
      if (ec == websocket::error::message_too_big) server_->Count(&ServerCounters::malformed);
      connection_->Close();
      connection_->state.reset();  // the handler's state (a running tuning) ends with the connection
      return;                      // closed, too big or broken: the session ends
    }
    server_->Count(&ServerCounters::websocket_messages);
    server_->slots.Touch(slot_);
    const std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    const Reply reply = server_->Answer(text, connection_);
    // Every reply, in order: the page matches them to its requests by id.
    if (!reply.body.is_null())
      Send(reply.body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "");
    ReadUnlessBacklogged();
  }

  // Reads the next request, unless the replies waiting exceed
  // kMaxQueuedReplyBytes: then OnWrite reads once they are written.
  void ReadUnlessBacklogged() {
    reading_ = ordered_bytes_ <= kMaxQueuedReplyBytes;
    if (reading_) Read();
  }

 public:
  // At most one write in flight. Waiting: the messages without a key (every
  // reply) in order, then one per key, a newer one replacing the older (a
  // slow client is sent the latest progress or frame, not a growing queue).
  void Send(std::string message, const std::string& replace_key, bool binary = false) {
    if (writing_) {
      if (replace_key.empty()) {
        ordered_bytes_ += message.size();
        ordered_.push_back({std::move(message), binary});
      } else {
        const auto replaced = waiting_.find(replace_key);
        if (replaced != waiting_.end()) {
          server_->Count(&ServerCounters::dropped_replies);
          if (replaced->second.binary) connection_->CountDropped();
        }
        waiting_[replace_key] = {std::move(message), binary};
      }
      return;
    }
    writing_ = true;
    out_ = std::move(message);
    ws_.binary(binary);
    ws_.async_write(net::buffer(out_),
                    beast::bind_front_handler(&WebSocketSession::OnWrite, shared_from_this()));
  }

 private:
  void OnWrite(beast::error_code ec, std::size_t) {
    writing_ = false;
    if (ec) return;
    server_->slots.Touch(slot_);
    Outgoing next;
    if (!ordered_.empty()) {
      next = std::move(ordered_.front());
      ordered_.pop_front();
      ordered_bytes_ -= next.bytes.size();
      if (!reading_) ReadUnlessBacklogged();
    } else if (!waiting_.empty()) {
      next = std::move(waiting_.begin()->second);
      waiting_.erase(waiting_.begin());
    } else {
      return;
    }
    Send(std::move(next.bytes), "", next.binary);
  }

  struct Outgoing {
    std::string bytes;
    bool binary = false;  // a binary message (a frame), else text (JSON)
  };

  websocket::stream<beast::tcp_stream> ws_;
  std::shared_ptr<Server::Impl> server_;
  std::shared_ptr<SessionConnection> connection_;
  beast::flat_buffer buffer_;
  std::string out_;
  Server::Impl::Slots::Id slot_;
  std::deque<Outgoing> ordered_;
  std::size_t ordered_bytes_ = 0;  // of ordered_
  std::map<std::string, Outgoing> waiting_;
  bool writing_ = false;
  bool reading_ = true;  // a read is in flight (or the session is ending)
};

bool SessionConnection::Post(const nlohmann::json& message, const std::string& replace_key) {
  if (closed_) return false;
  std::string text = message.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  net::post(executor_, [session = session_, text = std::move(text), replace_key]() mutable {
    if (auto s = session.lock()) s->Send(std::move(text), replace_key);
  });
  return true;
}

bool SessionConnection::PostBinary(std::string bytes, const std::string& replace_key) {
  if (closed_) return false;
  net::post(executor_, [session = session_, bytes = std::move(bytes), replace_key]() mutable {
    if (auto s = session.lock()) s->Send(std::move(bytes), replace_key, true);
  });
  return true;
}

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, std::shared_ptr<Server::Impl> server, const std::string& address)
      : stream_(std::move(socket)), server_(std::move(server)), slot_(server_->slots.Open(address)) {}
  ~HttpSession() {
    if (slot_) server_->slots.Close(slot_);
  }
  void Run() {
    server_->slots.OnStop(slot_, [weak = weak_from_this()] {
      beast::error_code ignored;
      if (auto self = weak.lock()) self->stream_.socket().close(ignored);
    });
    Read();
  }

 private:
  void Read() {
    // The previous request's body is gone; until this one's header and body
    // are in, the connection may be closed for a new one.
    server_->slots.ReleaseBody(slot_);
    server_->slots.Idle(slot_, [weak = weak_from_this()] {
      if (auto self = weak.lock()) self->Evict();
    });
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_->options.max_header_bytes));
    // The larger limit while the headers are parsed (Beast checks a
    // Content-Length against it there); OnHeader sets the request's own.
    parser_->body_limit(std::max(server_->options.max_body_bytes, server_->options.max_upload_bytes));
    stream_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(server_->options.header_timeout_s)));
    http::async_read_header(stream_, buffer_, *parser_,
                            beast::bind_front_handler(&HttpSession::OnHeader, shared_from_this()));
  }

  // An upload gets its own body limit, and is refused on its headers (token,
  // Host, Origin) before its body is read; every body is held in the
  // server's budget before it is read (413 when that is spent).
  void OnHeader(beast::error_code ec, std::size_t) {
    if (evicted_) return;  // its slot went to a newer connection
    if (ec) {
      OnRead(ec, 0);
      return;
    }
    stream_.expires_after(kBodyTimeout);
    server_->slots.Touch(slot_);  // idle from now while the body trickles
    if (IsUpload(parser_->get())) {
      const auto [status, why] = server_->Refusal(parser_->get());
      if (status != http::status::ok) {
        server_->Count(&ServerCounters::http_requests);
        server_->Count(&ServerCounters::refused);
        Refuse(status, why);
        return;
      }
    }
    parser_->body_limit(BodyLimit());
    const auto length = parser_->content_length();
    if (length && *length > BodyLimit()) {
      OnRead(http::error::body_limit, 0);
      return;
    }
    if (!HoldBody()) return;
    if (parser_->is_done()) {
      OnRead(ec, 0);
      return;
    }
    http::async_read(stream_, buffer_, *parser_,
                     beast::bind_front_handler(&HttpSession::OnRead, shared_from_this()));
  }

  // Holds an upload's bytes (its Content-Length, or its limit when chunked)
  // in the server's budget; answers 413 and returns false when that is spent.
  // A request's own body (64 KiB at most) always fits: uploads cannot crowd
  // out the page's requests.
  bool HoldBody() {
    if (!IsUpload(parser_->get())) return true;
    const auto length = parser_->content_length();
    const std::size_t bytes = length               ? static_cast<std::size_t>(*length)
                              : parser_->chunked() ? BodyLimit()
                                                   : 0;
    const std::size_t budget = server_->BodyBudget();
    if (bytes == 0 || server_->slots.HoldBody(slot_, bytes, budget)) return true;
    server_->Count(&ServerCounters::http_requests);
    server_->Count(&ServerCounters::over_budget);
    Refuse(http::status::payload_too_large, "the server holds " +
                                                std::to_string(server_->slots.body_bytes() >> 20) +
                                                " MiB of uploads, within " + std::to_string(budget >> 20) +
                                                " MiB for all: send it again once an upload has finished");
    return false;
  }

  void Refuse(http::status status, const std::string& why) {
    Response res = JsonResponse(parser_->get(), status, {{"error", why}});
    res.keep_alive(false);
    Write(std::move(res));
  }

  void OnRead(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout ||
        ec == net::error::operation_aborted || ec == net::error::connection_reset || ec == net::error::eof) {
      Close();
      return;
    }
    if (ec) {
      server_->Count(&ServerCounters::malformed);
      const http::status status = ec == http::error::body_limit ? http::status::payload_too_large
                                  : ec == http::error::header_limit
                                      ? http::status::request_header_fields_too_large
                                      : http::status::bad_request;
      Request bare;
      bare.version(11);
      bare.keep_alive(false);
      const std::string why = ec == http::error::body_limit ? "the body is larger than the limit of " +
                                                                  std::to_string(BodyLimit()) + " bytes"
                                                            : "malformed request: " + ec.message();
      Response res = JsonResponse(bare, status, {{"error", why}});
      res.keep_alive(false);
      Write(std::move(res));
      return;
    }
    Request req = parser_->release();
    if (websocket::is_upgrade(req)) {
      const auto [status, why] = server_->Refusal(req);
      if (status != http::status::ok || PathOf(std::string(req.target())) != "/ws") {
        server_->Count(&ServerCounters::refused);
        Response res = JsonResponse(req, status != http::status::ok ? status : http::status::not_found,
                                    {{"error", why.empty() ? "the WebSocket is at /ws" : why}});
        res.keep_alive(false);
        Write(std::move(res));
        return;
      }
      stream_.expires_never();
      const Server::Impl::Slots::Id slot = slot_;
      slot_ = 0;
      std::make_shared<WebSocketSession>(stream_.release_socket(), server_, slot)->Run(std::move(req));
      return;
    }
    Write(server_->Serve(req));
  }

  std::size_t BodyLimit() const {
    return parser_ && IsUpload(parser_->get()) ? server_->options.max_upload_bytes
                                               : server_->options.max_body_bytes;
  }

  void Write(Response res) {
    server_->slots.Busy(slot_);  // answering: not closed for a new connection
    auto shared = std::make_shared<Response>(std::move(res));
    http::async_write(stream_, *shared,
                      [self = shared_from_this(), shared](beast::error_code ec, std::size_t) {
                        if (ec || !shared->keep_alive())
                          self->Close();
                        else
                          self->Read();
                      });
  }

  // After the last reply: what the client still sends (an oversized body's
  // rest) is dropped for up to 1 s, so that it reads the reply, not a reset.
  void Close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.expires_after(std::chrono::seconds(1));
    Drain();
  }
  void Drain() {
    stream_.async_read_some(net::buffer(drained_),
                            [self = shared_from_this()](beast::error_code ec, std::size_t) {
                              if (!ec) self->Drain();
                            });
  }

  // Closed while waiting for its request header, to admit a new connection.
  void Evict() {
    evicted_ = true;
    slot_ = 0;  // already freed
    stream_.close();
  }

  beast::tcp_stream stream_;
  std::shared_ptr<Server::Impl> server_;
  Server::Impl::Slots::Id slot_;
  bool evicted_ = false;
  std::array<char, 4096> drained_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

void Accept(std::shared_ptr<Server::Impl> server) {
  server->acceptor.async_accept([server](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted) return;
    if (!ec) {
      beast::error_code ignored;
      const tcp::endpoint peer = socket.remote_endpoint(ec);
      const std::string address = peer.address().to_string();
      if (ec) {
        socket.close(ignored);  // gone already
      } else if (!server->MakeRoom(address)) {
        server->Count(&ServerCounters::turned_away);
        socket.close(ignored);
      } else {
        // Replies of 100 KB (the plot series) must not wait for delayed ACKs.
        socket.set_option(tcp::no_delay(true), ignored);
        std::make_shared<HttpSession>(std::move(socket), server, address)->Run();
      }
    }
    Accept(server);
  });
}

}  // namespace

Server::Server(ServerOptions options, ConnectionHandler handler, std::vector<Asset> assets)
    : impl_(std::make_shared<Impl>()) {
  impl_->options = std::move(options);
  impl_->handler = std::move(handler);
  impl_->assets = std::move(assets);
}

Server::~Server() { Stop(); }

void Server::SetUploadHandler(UploadHandler handler) { impl_->upload_handler = std::move(handler); }

Status Server::Start() {
  if (std::string why; !impl_->options.IsValid(&why)) return Status::InvalidInput(why);
  beast::error_code ec;
  const tcp::endpoint endpoint{net::ip::make_address(impl_->options.bind),
                               static_cast<unsigned short>(impl_->options.port)};
  impl_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl_->acceptor.bind(endpoint, ec);
  if (!ec) impl_->acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    return Status::RunnerFailed("cannot listen on " + impl_->options.bind + " port " +
                                std::to_string(impl_->options.port) + ": " + ec.message());
  impl_->port = impl_->acceptor.local_endpoint().port();
  Accept(impl_);
  return Status::Ok();
}

int Server::port() const { return impl_->port; }

void Server::Run() {
  impl_->io.run();
  // Stopped: every connection is closed and its handlers run to their end,
  // so that no session (each holds the Impl) is left holding the server.
  beast::error_code ignored;
  impl_->acceptor.close(ignored);
  impl_->slots.CloseAll();
  impl_->io.restart();
  impl_->io.run_for(std::chrono::seconds(2));
}

void Server::Stop() { impl_->io.stop(); }

ServerCounters Server::counters() const {
  std::lock_guard<std::mutex> lock(impl_->counters_mutex);
  return impl_->counters;
}

}  // namespace pidlab::server
