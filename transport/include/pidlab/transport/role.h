#pragma once
// The common part of the trio's three processes: a Role is an event-driven
// state machine over a Transport (no threads, no printing), so that tests can
// run all three and a client inside one memq:// LCM instance. The plant and
// disturbance roles live in plant_sim/, the controller role in controller/;
// the protocol they share is in docs/trio.md and protocol.h.

#include <csignal>
#include <functional>
#include <memory>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_ready.hpp>
#include <string>

#include "pidlab/transport/episode_spec.h"
#include "pidlab/transport/transport.h"

namespace pidlab::transport {

/// Where a role reports (one line per episode unless verbose). May be empty.
using LogFn = std::function<void(const std::string& line)>;

struct RoleCounters {
  long episodes = 0;
  long foreign = 0;      // messages of another episode (or before any config)
  long duplicates = 0;   // repeated or out-of-order steps, ignored or re-answered
  long bad_configs = 0;  // configurations that failed validation
  long retransmits = 0;  // messages resent after a silence
  long conflicts = 0;    // two different payloads for the same episode, channel and step
};

/// Common part: answers PING with ALIVE, acknowledges configurations.
class Role {
 public:
  Role(Transport* transport, std::string role, LogFn log, bool verbose);
  virtual ~Role() = default;
  /// Time-driven work (resends, deadlines). Call at least every
  /// retransmit interval; `now_s` is NowSeconds().
  virtual void Tick(double now_s) { (void)now_s; }
  /// The longest a caller may wait before the next Tick.
  virtual double MaxWait() const { return 0.05; }
  const RoleCounters& counters() const { return counters_; }
  /// True once the role cannot go on (it has said why): ServeRole returns.
  virtual bool Halted() const { return false; }
  const std::string& role() const { return role_; }

 protected:
  /// Called for a configuration of a new episode id, already validated.
  virtual void StartEpisode(const EpisodeSpec& spec) = 0;
  void Ack(int64_t episode_id);
  void Log(const std::string& line) const;
  void Verbose(const std::string& line) const;

  Transport* transport_;
  std::string role_;
  LogFn log_;
  bool verbose_;
  RoleCounters counters_;
  int64_t episode_id_ = 0;  // current episode, 0 before the first

 private:
  void OnConfig(const pidlab::lcmt_episode_config& msg);
  void OnReady(const pidlab::lcmt_ready& msg);
};

/// Serves `role` until *stop becomes true (checked between waits). Returns 0,
/// 1 on an LCM error, or 2 when the role halted (Role::Halted).
int ServeRole(Transport* transport, Role* role, const volatile std::sig_atomic_t* stop);

}  // namespace pidlab::transport
