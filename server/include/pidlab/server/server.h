#pragma once
// The workbench's HTTP and WebSocket server (docs/workbench.md), on
// Boost.Beast: static assets, one JSON request route (POST /api/request) and
// the same requests over a WebSocket (/ws). What a request means is the
// Handler's business (`pidlab serve` passes the spec evaluation); this
// library only carries it, safely:
//  - it binds the address it is given (127.0.0.1 by default) and, when a
//    token is set (required for any other address), refuses every request
//    without it (401): `?token=` in the URL or `Authorization: Bearer`;
//  - the Host header must name this server (no DNS rebinding) and a present
//    Origin must be this server's own (403), for HTTP and the WebSocket;
//  - headers, bodies and WebSocket messages are bounded (431, 413, close
//    1009); a malformed request gets 400 and its connection closes; the
//    server keeps serving;
//  - a request header must be complete within `header_timeout_s`, its body
//    within `body_timeout_s` after it (408 and the connection closed: a body
//    that trickles holds its slot that long at most), and a WebSocket that does not answer a ping within
//    `websocket_idle_timeout_s` is closed; when the connections (all, or one
//    address's) are at their cap, the one idle longest (waiting for a header,
//    trickling a body, a quiet WebSocket) is closed to admit the new one (a
//    slow loris loses its slot, not the next client);
//  - the uploads held in memory at once are bounded in total
//    (`max_bodies_bytes`): one that would pass it gets 413 on its header;
//  - request JSON nested deeper than 64 levels is refused (400) before it is
//    parsed;
//  - every reply to a WebSocket request is sent, in order; only the
//    handler's progress and frames are replaced by newer ones for a slow
//    client, and a client that does not read is not read from either.
// One thread runs the io_context and the Handler (requests are evaluations of
// microseconds to milliseconds); longer work (a tuning) runs on threads of the
// handler's, which send their messages later through the request's Connection.

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"

namespace pidlab::server {

struct ServerOptions {
  /// The address to bind (IPv4 or IPv6 literal).
  std::string bind = "127.0.0.1";
  /// The port; 0 picks a free one (Server::port() says which).
  int port = 8080;
  /// Required on every request when not empty; must be set (>= 16
  /// characters) unless `bind` is a loopback address.
  std::string token;
  std::size_t max_header_bytes = 8 * 1024;
  std::size_t max_body_bytes = 64 * 1024;
  std::size_t max_message_bytes = 64 * 1024;
  /// The body of POST /api/upload (a log); 413 above.
  std::size_t max_upload_bytes = 64 * 1024 * 1024;
  /// Upload bodies held in memory at once, every connection's together (at
  /// least max_upload_bytes): an upload that would pass it is refused with
  /// 413 on its header, before it is read. Other bodies are bounded by
  /// max_body_bytes on each of max_connections (4 MiB in all by default).
  std::size_t max_bodies_bytes = 64 * 1024 * 1024;
  /// Connections open at once. A new one beyond it closes the connection
  /// idle longest: one waiting for its request header, trickling its body,
  /// or a WebSocket since its last message (only a connection being answered
  /// is never closed so); with none to close, the new one is closed on accept.
  int max_connections = 64;
  /// Connections open at once from one client address, 1..max_connections;
  /// the same rule as max_connections among that address's connections.
  int max_connections_per_address = 16;
  /// Seconds from a connection's accept (or its previous reply) to a complete
  /// request header, 0.1..600; the connection is closed after it.
  double header_timeout_s = 5.0;
  /// Seconds from a complete request header to its complete body (a request
  /// or an upload), 0.1..3600, however slowly it trickles: past them the
  /// request is answered 408 with one line and its connection closed. 30 s
  /// takes a 64 MiB upload at 2.2 MB/s or faster.
  double body_timeout_s = 30.0;
  /// Seconds a WebSocket may go without a byte from its client, 0.1..3600:
  /// it is pinged after half of them and closed after all of them.
  double websocket_idle_timeout_s = 60.0;

  /// Names the field, its value and the rule on failure.
  bool IsValid(std::string* error) const;
};

/// Whether `address` is a loopback address (127.0.0.0/8, ::1).
bool IsLoopback(const std::string& address);

/// A handler's answer: an HTTP status (200, 400 for a bad request) and a JSON body.
struct Reply {
  int status = 200;
  nlohmann::json body;
};
/// Answers one request object. Exceptions become 500 with their message.
using Handler = std::function<Reply(const nlohmann::json& request)>;

/// A WebSocket connection as its requests' handler sees it: messages sent
/// later, from any thread (a tuning's progress and result). A message posted
/// with a `replace_key` replaces the one of the same key still waiting to be
/// written (progress: only the latest matters); one without is always sent,
/// in order.
class Connection {
 public:
  virtual ~Connection() = default;
  /// Queues `message` on the connection; false if it has closed.
  virtual bool Post(const nlohmann::json& message, const std::string& replace_key = "") = 0;
  /// Queues `bytes` as one binary WebSocket message, with the same
  /// replace-latest rule (the live scope's frames); false if it has closed.
  virtual bool PostBinary(std::string bytes, const std::string& replace_key = "") = 0;
  virtual bool closed() const = 0;
  /// This connection's binary messages (frames) replaced by a newer one of
  /// the same key before they were written (ServerCounters::dropped_replies
  /// counts every replaced message of every connection).
  long dropped() const { return dropped_; }
  /// The handler's own state for this connection (its running tuning),
  /// touched on the server's thread only; released when the connection closes.
  std::shared_ptr<void> state;

 protected:
  std::atomic<long> dropped_{0};
};

/// Answers one request with the connection it came on (null over HTTP).
using ConnectionHandler =
    std::function<Reply(const nlohmann::json& request, const std::shared_ptr<Connection>& connection)>;

/// Answers `POST /api/upload?name=NAME` (NAME percent-decoded, as sent) with
/// the raw body, at most ServerOptions::max_upload_bytes (413 above, before the
/// handler); the token, Host and Origin rules of /api/request apply, checked
/// on the headers before the body is read.
using UploadHandler = std::function<Reply(const std::string& name, const std::string& body)>;

/// A static file served at `path` ("/" and "/app.js").
struct Asset {
  std::string path;
  std::string content_type;
  std::string body;
};

/// What the server has seen, for tests and the hostile-input test.
struct ServerCounters {
  long http_requests = 0;
  long websocket_messages = 0;
  long refused = 0;          // 401 and 403
  long malformed = 0;        // 400, 413, 431 and WebSocket messages that are not JSON objects
  long dropped_replies = 0;  // replaced by a newer one for a slow client
  long evicted = 0;          // closed while idle (the one idle longest), to admit a new connection
  long over_budget = 0;      // 413: the uploads in memory at their total limit
  long turned_away = 0;      // closed on accept: every slot held by connections that may not be evicted
  long late_bodies = 0;      // 408: a body not complete within body_timeout_s of its header
};

class Server {
 public:
  Server(ServerOptions options, Handler handler, std::vector<Asset> assets);
  Server(ServerOptions options, ConnectionHandler handler, std::vector<Asset> assets);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Serves POST /api/upload with `handler` (404 without one); call before Start.
  void SetUploadHandler(UploadHandler handler);
  /// Binds and listens. A failed Status naming the address, the port and
  /// why: kInvalidInput for invalid options, kRunnerFailed if it cannot listen.
  Status Start();
  /// The bound port (after Start).
  int port() const;
  /// Serves until Stop(); call after Start.
  void Run();
  /// From any thread: Run returns.
  void Stop();
  ServerCounters counters() const;

  /// The implementation (server.cc); public only so that its sessions can hold it.
  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace pidlab::server
