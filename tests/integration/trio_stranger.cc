// trio_stranger URL PREFIX SECONDS: publishes garbage and foreign-episode
// messages on the trio's channels for SECONDS, as a stranger on the network
// would. Seeded, so a run is reproducible.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_disturbance_block.hpp>
#include <pidlab/lcmt_disturbance_request.hpp>
#include <pidlab/lcmt_disturbance_sample.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "pidlab/transport/transport.h"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: trio_stranger URL PREFIX SECONDS\n");
    return 2;
  }
  lcm::LCM lcm(argv[1]);
  if (!lcm.good()) return 1;
  // The per-step channels travel on the trio's step lanes (transport.h).
  const std::string y_url = pidlab::transport::StepLaneUrl(argv[1], pidlab::transport::kPlantOutputLane);
  const std::string u_url = pidlab::transport::StepLaneUrl(argv[1], pidlab::transport::kControlLane);
  lcm::LCM lcm_y(y_url.empty() ? argv[1] : y_url), lcm_u(u_url.empty() ? argv[1] : u_url);
  if (!lcm_y.good() || !lcm_u.good()) return 1;
  const std::string p = argv[2];
  const double seconds = std::atof(argv[3]);
  std::mt19937 rng(1234);
  const char* channels[] = {
      "EPISODE_CONFIG",     "READY",      "PLANT_OUTPUT",        "CONTROL",          "DISTURBANCE", "SUMMARY",
      "TRAJECTORY_REQUEST", "TRAJECTORY", "DISTURBANCE_REQUEST", "DISTURBANCE_BLOCK"};
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  long sent = 0;
  for (int64_t i = 0; std::chrono::steady_clock::now() < end; ++i) {
    // Garbage bytes on every channel.
    std::vector<unsigned char> junk(1 + rng() % 200);
    for (auto& b : junk) b = static_cast<unsigned char>(rng());
    lcm.publish(p + channels[i % 10], junk.data(), static_cast<unsigned>(junk.size()));
    (i % 2 ? lcm_y : lcm_u).publish(p + channels[i % 10], junk.data(), static_cast<unsigned>(junk.size()));
    // Well-formed messages of a foreign episode, with plausible steps.
    const int64_t foreign = 777000 + (i % 5);
    pidlab::lcmt_plant_output y{};
    y.episode_id = foreign;
    y.step = i % 50;
    y.y = 1e6;
    lcm.publish(p + "PLANT_OUTPUT", &y);
    lcm_y.publish(p + "PLANT_OUTPUT", &y);
    pidlab::lcmt_control_command u{};
    u.episode_id = foreign;
    u.step = i % 50;
    u.u = -1e6;
    lcm.publish(p + "CONTROL", &u);
    lcm_u.publish(p + "CONTROL", &u);
    pidlab::lcmt_disturbance_sample n{};
    n.episode_id = foreign;
    n.step = i % 50;
    n.n = 1e6;
    lcm.publish(p + "DISTURBANCE", &n);
    pidlab::lcmt_disturbance_request q{};
    q.episode_id = foreign;
    q.step = i % 50;
    q.samples = 1000000;
    lcm.publish(p + "DISTURBANCE_REQUEST", &q);
    pidlab::lcmt_disturbance_block b{};
    b.episode_id = foreign;
    b.step = i % 50;
    b.dt_s = 0.01;
    b.count = 3;
    b.n = {1e6, 1e6, 1e6};
    lcm.publish(p + "DISTURBANCE_BLOCK", &b);
    // Right type on the wrong channel.
    lcm.publish(p + "CONTROL", &y);
    lcm.publish(p + "DISTURBANCE_BLOCK", &u);
    sent += 8;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  std::printf("stranger: %ld messages sent\n", sent);
  return 0;
}
