#pragma once
// The server's one budget of connections and of request bodies in memory
// (server.cc): every open connection with its client's address, since when it
// has been idle and how to close it, and the body bytes it holds. A new
// connection always finds room while any connection is idle: the one idle
// longest is closed for it, whatever it is doing (waiting for a request
// header, trickling a body, a WebSocket with nothing to say). Only a
// connection answering a request is never closed so. Touched on the
// server's thread only.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

namespace pidlab::server::internal {

class Slots {
 public:
  using Id = std::uint64_t;
  using Clock = std::chrono::steady_clock;

  /// A new connection from `address`: busy until Idle().
  Id Open(const std::string& address);
  /// Frees `id`'s slot and the body bytes it held (nothing if already freed).
  void Close(Id id);
  /// From now on `id` waits (for a request header, the rest of a body, a
  /// WebSocket message) and may be closed with `close` to admit a new
  /// connection; its idle time starts now.
  void Idle(Id id, std::function<void()> close);
  /// `id` did something (a WebSocket message read or written): its idle time
  /// starts again.
  void Touch(Id id);
  /// `id` is answering a request: never closed for a new one until Idle().
  void Busy(Id id);
  /// How to close `id` whatever it is doing, when the server stops.
  void OnStop(Id id, std::function<void()> close);
  /// Closes every connection (the server has stopped): their handlers then
  /// end, and with them the sessions that hold the server.
  void CloseAll();
  /// The connections open, of `address` only if not null.
  int Count(const std::string* address) const;
  /// Closes the connection (of `address` if not null) idle longest and frees
  /// its slot now; false if none is idle.
  bool EvictIdleLongest(const std::string* address);
  /// Whether a new connection from `address` may open under the caps (of one
  /// address, of all), after closing the connection idle longest where one
  /// is reached (that address's own first); how many were closed in *evicted.
  bool MakeRoom(const std::string& address, int per_address_cap, int cap, int* evicted);
  /// Holds `bytes` of request body for `id` if every body held stays within
  /// `budget` bytes; false, and nothing held, if not.
  bool HoldBody(Id id, std::size_t bytes, std::size_t budget);
  /// Frees the body bytes `id` holds.
  void ReleaseBody(Id id);
  /// The body bytes held by every connection.
  std::size_t body_bytes() const { return body_bytes_; }

 private:
  struct Entry {
    std::string address;
    Clock::time_point since;
    std::function<void()> close;  // set while idle
    std::function<void()> stop;   // closes it whatever it is doing
    std::size_t body_bytes = 0;
  };
  std::map<Id, Entry> entries_;
  Id last_ = 0;
  std::size_t body_bytes_ = 0;
};

}  // namespace pidlab::server::internal
