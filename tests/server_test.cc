// The workbench server (pidlab::server) on 127.0.0.1 with a handler of the
// test's own: slots that a slow client, a trickling body or a quiet
// WebSocket cannot hold against a new one, the request-header deadline, the
// WebSocket's ping, the budget of bodies in memory, the JSON depth bound, a
// field of the wrong type, and every WebSocket reply delivered in order to a
// client that reads late.

#include "pidlab/server/server.h"

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "test_status.h"

namespace pidlab::server {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

// A server on a free port of 127.0.0.1, run on a thread of its own until the
// fixture ends. Its handler answers {"ok": true} and `padding_bytes` of 'x'.
class Served {
 public:
  explicit Served(ServerOptions options, std::size_t padding_bytes = 0, Handler handler = nullptr) {
    options.bind = "127.0.0.1";
    options.port = 0;
    const std::string padding(padding_bytes, 'x');
    if (!handler)
      handler = [padding](const nlohmann::json&) { return Reply{200, {{"ok", true}, {"padding", padding}}}; };
    dut_ = std::make_unique<Server>(options, std::move(handler), std::vector<Asset>{});
    dut_->SetUploadHandler([](const std::string&, const std::string& body) {
      return Reply{200, {{"bytes", body.size()}}};
    });
    std::string error;
    EXPECT_TRUE(IsOk(dut_->Start()));
    thread_ = std::thread([this] { dut_->Run(); });
  }
  ~Served() {
    dut_->Stop();
    thread_.join();
  }
  int port() const { return dut_->port(); }
  ServerCounters counters() const { return dut_->counters(); }
  std::string host() const { return "127.0.0.1:" + std::to_string(port()); }

 private:
  std::unique_ptr<Server> dut_;
  std::thread thread_;
};

// A plain TCP client of the served port, from `source` (an address of the
// loopback: 127.0.0.2 is another client address).
class Client {
 public:
  Client(const Served& served, const std::string& source = "127.0.0.1") : socket_(io_) {
    socket_.open(tcp::v4());
    socket_.bind({net::ip::make_address(source), 0});
    socket_.connect({net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(served.port())});
    host_ = served.host();
  }
  void Send(const std::string& bytes) { net::write(socket_, net::buffer(bytes)); }
  // A keep-alive request and its response's status.
  int Get(const std::string& path) {
    Send("GET " + path + " HTTP/1.1\r\nHost: " + host_ + "\r\n\r\n");
    return ReadStatus();
  }
  int ReadStatus() {
    http::response<http::string_body> res;
    beast::error_code ec;
    http::read(socket_, buffer_, res, ec);
    return ec ? -1 : res.result_int();
  }
  // Whether the server has closed the connection (a read ends without a byte).
  bool ClosedByServer() {
    char byte;
    beast::error_code ec;
    const std::size_t n = socket_.read_some(net::buffer(&byte, 1), ec);
    return n == 0 && ec;
  }
  tcp::socket& socket() { return socket_; }
  const std::string& host() const { return host_; }

 private:
  net::io_context io_;
  tcp::socket socket_;
  beast::flat_buffer buffer_;
  std::string host_;
};

// A connection that has had one answer and has sent part of its next header.
std::unique_ptr<Client> SlowClient(const Served& served, const std::string& source = "127.0.0.1") {
  auto client = std::make_unique<Client>(served, source);
  EXPECT_EQ(client->Get("/api/health"), 200);
  client->Send("GET /api/health HTTP/1.1\r\nHo");
  return client;
}

// Status and body of POST /api/request with `body`, on a fresh connection.
std::pair<int, std::string> PostRequest(const Served& served, const std::string& body) {
  Client client(served);
  http::request<http::string_body> req{http::verb::post, "/api/request", 11};
  req.set(http::field::host, client.host());
  req.set(http::field::content_type, "application/json");
  req.body() = body;
  req.prepare_payload();
  http::write(client.socket(), req);
  http::response<http::string_body> res;
  beast::flat_buffer buffer;
  http::read(client.socket(), buffer, res);
  return {res.result_int(), res.body()};
}

std::string Nested(int depth) {
  return "{\"a\":" + std::string(depth - 1, '[') + std::string(depth - 1, ']') + "}";
}

TEST(ServerOptions, RefusesAPerAddressCapAboveTheGlobalCap) {
  ServerOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  EXPECT_LT(options.max_connections_per_address, options.max_connections);
  options.max_connections_per_address = options.max_connections + 1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_connections_per_address 65"), std::string::npos) << error;
  options.max_connections_per_address = 0;
  EXPECT_FALSE(options.IsValid(&error));
}

TEST(ServerOptions, RefusesAHeaderTimeoutOutsideItsRange) {
  ServerOptions options;
  std::string error;
  for (double seconds : {0.0, 0.05, 601.0, std::nan("")}) {
    options.header_timeout_s = seconds;
    EXPECT_FALSE(options.IsValid(&error)) << seconds;
    EXPECT_NE(error.find("header_timeout_s"), std::string::npos) << error;
  }
}

TEST(ServerOptions, RefusesABodyTimeoutOutsideItsRange) {
  ServerOptions options;
  std::string error;
  EXPECT_EQ(options.body_timeout_s, 30.0);
  for (double seconds : {0.0, 0.05, 3601.0, -1.0, std::nan("")}) {
    options.body_timeout_s = seconds;
    EXPECT_FALSE(options.IsValid(&error)) << seconds;
    EXPECT_NE(error.find("body_timeout_s"), std::string::npos) << error;
  }
  options.body_timeout_s = 0.1;
  EXPECT_TRUE(options.IsValid(&error)) << error;
}

TEST(Server, ClosesAConnectionWhoseHeaderIsNotCompleteInTime) {
  ServerOptions options;
  options.header_timeout_s = 0.3;
  Served served(options);
  const auto start = std::chrono::steady_clock::now();  // before the accept that starts the deadline
  Client slow(served);
  slow.Send("GET / HTTP/1.1\r\nHo");
  EXPECT_TRUE(slow.ClosedByServer());
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(waited_s, 0.29);
  EXPECT_LT(waited_s, 3.0);
}

TEST(Server, EvictsTheConnectionWaitingLongestForItsHeaderWhenEverySlotIsTaken) {
  ServerOptions options;
  options.max_connections = 4;
  options.max_connections_per_address = 4;
  Served served(options);
  std::vector<std::unique_ptr<Client>> slow;
  for (int i = 0; i < 4; ++i) slow.push_back(SlowClient(served));
  Client fresh(served);
  EXPECT_EQ(fresh.Get("/api/health"), 200);
  EXPECT_TRUE(slow[0]->ClosedByServer());
  slow[1]->Send("st: " + slow[1]->host() + "\r\n\r\n");  // the rest of its header: still served
  EXPECT_EQ(slow[1]->ReadStatus(), 200);
  EXPECT_EQ(served.counters().evicted, 1);
  EXPECT_EQ(served.counters().turned_away, 0);
}

TEST(Server, CapsTheConnectionsOfOneAddressBelowTheGlobalCap) {
  ServerOptions options;
  options.max_connections = 8;
  options.max_connections_per_address = 2;
  Served served(options);
  auto first = SlowClient(served);
  auto second = SlowClient(served);
  auto other = SlowClient(served, "127.0.0.2");  // another address: its own two slots
  EXPECT_EQ(served.counters().evicted, 0);
  Client third(served);
  EXPECT_EQ(third.Get("/api/health"), 200);
  EXPECT_TRUE(first->ClosedByServer());
  EXPECT_EQ(served.counters().evicted, 1);
  other->Send("st: " + other->host() + "\r\n\r\n");
  EXPECT_EQ(other->ReadStatus(), 200);
}

// A WebSocket client of the served port from `source`, its handshake done.
std::unique_ptr<websocket::stream<tcp::socket>> OpenWebSocket(net::io_context* io, const Served& served,
                                                              const std::string& source = "127.0.0.1") {
  auto ws = std::make_unique<websocket::stream<tcp::socket>>(*io);
  ws->next_layer().open(tcp::v4());
  ws->next_layer().bind({net::ip::make_address(source), 0});
  ws->next_layer().connect({net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(served.port())});
  ws->handshake(served.host(), "/ws");
  return ws;
}

int AskId(websocket::stream<tcp::socket>* ws, int id) {
  ws->write(net::buffer(nlohmann::json{{"id", id}}.dump()));
  beast::flat_buffer buffer;
  ws->read(buffer);
  return nlohmann::json::parse(beast::buffers_to_string(buffer.data()))["id"].get<int>();
}

TEST(Server, EvictsTheWebSocketIdleLongestWhenEverySlotIsTaken) {
  ServerOptions options;
  options.max_connections = 2;
  options.max_connections_per_address = 2;
  Served served(options);
  net::io_context io;
  auto quiet = OpenWebSocket(&io, served);
  auto talking = OpenWebSocket(&io, served);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(AskId(talking.get(), 7), 7);  // its idle time starts again
  Client fresh(served);
  EXPECT_EQ(fresh.Get("/api/health"), 200);
  beast::flat_buffer buffer;
  beast::error_code ec;
  quiet->read(buffer, ec);
  EXPECT_TRUE(ec) << "the quiet WebSocket is still open";
  EXPECT_EQ(AskId(talking.get(), 8), 8);
  EXPECT_EQ(served.counters().evicted, 1);
  EXPECT_EQ(served.counters().turned_away, 0);
}

TEST(Server, ClosesAWebSocketThatDoesNotAnswerItsPing) {
  ServerOptions options;
  options.websocket_idle_timeout_s = 0.4;
  Served served(options);
  net::io_context io;
  // A raw socket after the handshake: it never reads, so it never answers a ping.
  auto ws = OpenWebSocket(&io, served);
  tcp::socket& socket = ws->next_layer();
  const auto start = std::chrono::steady_clock::now();
  std::string bytes;
  char chunk[256];
  beast::error_code ec;
  while (!ec) bytes.append(chunk, socket.read_some(net::buffer(chunk), ec));
  const double closed_after_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_GE(bytes.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0x89) << "the first frame is not a ping";
  EXPECT_GE(closed_after_s, 0.35);
  EXPECT_LT(closed_after_s, 3.0);
}

TEST(Server, EvictsAConnectionTricklingItsBodyToAdmitANewOne) {
  ServerOptions options;
  options.max_connections = 2;
  options.max_connections_per_address = 2;
  Served served(options);
  std::vector<std::unique_ptr<Client>> slow;
  for (int i = 0; i < 2; ++i) {
    slow.push_back(std::make_unique<Client>(served));
    slow.back()->Send("POST /api/request HTTP/1.1\r\nHost: " + slow.back()->host() +
                      "\r\nContent-Length: 100\r\n\r\n{\"a\":");
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  Client fresh(served, "127.0.0.2");
  EXPECT_EQ(fresh.Get("/api/health"), 200);
  EXPECT_TRUE(slow[0]->ClosedByServer());
  EXPECT_EQ(served.counters().evicted, 1);
}

// Status and body of POST /api/upload with `body`, on a fresh connection.
std::pair<int, std::string> PostUpload(const Served& served, const std::string& body) {
  Client client(served);
  http::request<http::string_body> req{http::verb::post, "/api/upload?name=a.lcmlog", 11};
  req.set(http::field::host, client.host());
  req.body() = body;
  req.prepare_payload();
  http::write(client.socket(), req);
  http::response<http::string_body> res;
  beast::flat_buffer buffer;
  beast::error_code ec;
  http::read(client.socket(), buffer, res, ec);
  return {ec ? -1 : res.result_int(), res.body()};
}

TEST(Server, RefusesAnUploadThatWouldPassTheBudgetOfEveryUploadInMemory) {
  ServerOptions options;
  options.max_upload_bytes = 4096;
  options.max_bodies_bytes = 6000;
  Served served(options);
  Client holding(served);
  holding.Send("POST /api/upload?name=b.lcmlog HTTP/1.1\r\nHost: " + holding.host() +
               "\r\nContent-Length: 4000\r\n\r\nLCM");
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const auto [status, body] = PostUpload(served, std::string(3000, 'x'));
  EXPECT_EQ(status, 413);
  EXPECT_NE(body.find("MiB of uploads"), std::string::npos) << body;
  EXPECT_EQ(served.counters().over_budget, 1);
  EXPECT_EQ(PostRequest(served, "{\"x\":\"" + std::string(3000, 'x') + "\"}").first, 200);  // not an upload
  EXPECT_EQ(PostUpload(served, std::string(1000, 'x')).first, 200);                         // still fits
}

TEST(Server, AnswersAFieldOfTheWrongJsonTypeWith400AndOneLine) {
  Served served(ServerOptions{}, 0, [](const nlohmann::json& request) {
    return Reply{200, {{"type", request.value("type", std::string())}}};
  });
  for (const std::string body : {"{\"type\":5}", "{\"type\":null}", "{\"type\":[]}", "{\"type\":{}}"}) {
    const auto [status, reply] = PostRequest(served, body);
    EXPECT_EQ(status, 400) << body;
    EXPECT_EQ(reply.find("json.exception"), std::string::npos) << reply;
    EXPECT_EQ(reply.find('\n'), std::string::npos) << reply;
  }
  EXPECT_EQ(PostRequest(served, "{\"type\":\"fields\"}").first, 200);
}

TEST(Server, RefusesJsonNestedDeeperThan64LevelsBeforeParsingIt) {
  Served served(ServerOptions{});
  EXPECT_EQ(PostRequest(served, Nested(64)).first, 200);
  const auto [status, body] = PostRequest(served, Nested(65));
  EXPECT_EQ(status, 400);
  EXPECT_NE(body.find("JSON is nested deeper than 64 levels"), std::string::npos) << body;
  EXPECT_EQ(PostRequest(served, Nested(30000)).first, 400);
  // Brackets inside a string are text, not nesting.
  EXPECT_EQ(PostRequest(served, "{\"s\":\"" + std::string(1000, '[') + "\\\"{{\"}").first, 200);
  EXPECT_EQ(served.counters().malformed, 2);
}

TEST(Server, SendsEveryWebSocketReplyInOrderToAClientThatReadsLate) {
  // 200 replies of 32 KiB (6.4 MiB) fill the socket buffers while the
  // client has not read: the server holds most of them in its queue.
  constexpr int kRequests = 200;
  Served served(ServerOptions{}, 32 * 1024);
  net::io_context io;
  websocket::stream<tcp::socket> ws(io);
  ws.next_layer().connect({net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(served.port())});
  ws.handshake(served.host(), "/ws");
  for (int id = 0; id < kRequests; ++id) ws.write(net::buffer(nlohmann::json{{"id", id}}.dump()));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the slow reader
  for (int id = 0; id < kRequests; ++id) {
    beast::flat_buffer buffer;
    ws.read(buffer);
    ASSERT_EQ(nlohmann::json::parse(beast::buffers_to_string(buffer.data()))["id"], id);
  }
  EXPECT_EQ(served.counters().websocket_messages, kRequests);
  EXPECT_EQ(served.counters().dropped_replies, 0);
}

}  // namespace
}  // namespace pidlab::server
