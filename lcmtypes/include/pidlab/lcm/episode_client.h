#pragma once
// Runs one episode of the sampled loop over a running trio: the LCM backend of
// `pidlab evaluate`. Publishes the configuration until the plant, controller
// and disturbance acknowledge it, records y, u and n of every step from the
// trajectory chunks the plant streams (it does not wake for every lockstep
// message), asks the plant to resend whatever it missed, and reports a silent
// process by name.

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "pidlab/lcm/episode_config.h"
#include "pidlab/lcm/transport.h"
#include "pidlab/tuner/evaluation.h"

namespace pidlab::lcm_trio {

struct EpisodeClientOptions {
  std::string lcm_url = kDefaultLcmUrl;
  TransportOptions transport;
  RecoveryOptions recovery;
  /// How long to wait for all three acknowledgements, s.
  double start_timeout_s = 3.0;
  /// Upper bound on one episode, s.
  double episode_timeout_s = 600.0;

  bool IsValid(std::string* error) const;
};

struct EpisodeClientStats {
  long episodes = 0;
  long steps = 0;         // lockstep steps run
  double seconds = 0.0;   // wall time from the first acknowledgement to the last step
  long resent_steps = 0;  // steps the client had to ask the plant for again
  double StepsPerSecond() const { return seconds > 0.0 ? static_cast<double>(steps) / seconds : 0.0; }
};

class EpisodeClient {
 public:
  /// Throws std::runtime_error if LCM cannot be initialised on the URL.
  explicit EpisodeClient(const EpisodeClientOptions& options);
  ~EpisodeClient();

  /// A SampledRunner: y at every step k = 0..TotalSteps() in *y_all, every
  /// step in *trajectory when not null. False with a one-line *error naming
  /// the silent process on failure.
  bool Run(const Plant& plant, const PidGains& gains, const LoopOptions& options,
           const DisturbanceOptions& disturbance, std::vector<double>* y_all,
           std::vector<SampledStep>* trajectory, std::string* error);

  SampledRunner AsRunner();
  const EpisodeClientStats& stats() const { return stats_; }
  const TransportCounters& counters() const;

 private:
  struct State;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Transport> transport_;
  std::unique_ptr<State> state_;
  EpisodeClientOptions options_;
  EpisodeClientStats stats_;
};

}  // namespace pidlab::lcm_trio
