#include "pidlab/server/server.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
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

#include "impl.h"
#include "pidlab/spec/field.h"
#include "slots.h"
#include "url.h"

namespace pidlab::server {
namespace {
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using internal::IsUpload;
using internal::JsonResponse;
using internal::PathOf;
using internal::Request;
using internal::Response;

// WebSocket replies waiting beyond this many bytes: the session stops reading
// requests until they are written (a client that sends and never reads).
constexpr std::size_t kMaxQueuedReplyBytes = 1 << 20;

// A reply's write: the time a client that does not read may take.
constexpr std::chrono::seconds kReplyTimeout{30};

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

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
    timeout.idle_timeout = Seconds(server_->options.websocket_idle_timeout_s);
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
    stream_.expires_after(Seconds(server_->options.header_timeout_s));
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
    ReadBody();
  }

  // The body, complete within body_timeout_s of its header however it
  // trickles: past it, 408 and the connection closed (OnRead).
  void ReadBody() {
    stream_.expires_never();  // the body's deadline is body_timer_'s, which answers
    reading_body_ = true;
    body_timer_.expires_after(Seconds(server_->options.body_timeout_s));
    body_timer_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      auto self = weak.lock();
      if (ec || !self || !self->reading_body_) return;
      self->body_late_ = true;
      beast::error_code ignored;
      self->stream_.socket().cancel(ignored);
    });
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
    reading_body_ = false;
    body_timer_.cancel();
    if (body_late_ && ec && !evicted_) {
      body_late_ = false;
      server_->Count(&ServerCounters::late_bodies);
      Refuse(http::status::request_timeout, "the body did not arrive within " +
                                                spec::FormatNumber(server_->options.body_timeout_s) +
                                                " s of its header (pidlab serve --body-timeout)");
      return;
    }
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
    stream_.expires_after(kReplyTimeout);
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
  net::steady_timer body_timer_{stream_.get_executor()};
  bool reading_body_ = false;  // the body is being read: body_timer_ may cut it
  bool body_late_ = false;     // body_timer_ cut it: answered 408
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
