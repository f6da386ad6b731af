// Test helper: copies an LCM log, damaging it on purpose.
//   replay_log_tamper IN OUT alter-command STEP   u of step STEP (of the episode with a disturbance)
//                                                 moved up by one ulp in every CONTROL message and
//                                                 TRAJECTORY chunk that holds it (the CONTROL
//                                                 messages travel on a step lane that lcm-logger on
//                                                 the trio's URL does not hear: the chunks carry u)
//   replay_log_tamper IN OUT inject-garbage       foreign, unknown-type and undecodable events
//                                                 between the events of the episode
//   replay_log_tamper IN OUT inject-orphan        one forged plant output of each of the episodes
//                                                 987654321..3, whose configuration is in no log
//                                                 (orphans)
#include <cmath>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <pidlab/lcmt_control_command.hpp>
#include <pidlab/lcmt_episode_config.hpp>
#include <pidlab/lcmt_plant_output.hpp>
#include <pidlab/lcmt_trajectory_chunk.hpp>
#include <random>
#include <string>
#include <vector>

namespace {

void Put(lcm::LogFile* out, const lcm::LogEvent& ev, int64_t* num) {
  lcm::LogEvent copy = ev;
  copy.eventnum = (*num)++;
  out->writeEvent(&copy);
}

void PutBytes(lcm::LogFile* out, const std::string& channel, std::vector<uint8_t> bytes, int64_t* num) {
  lcm::LogEvent ev;
  ev.timestamp = 0;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(bytes.size());
  ev.data = bytes.data();
  Put(out, ev, num);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: replay_log_tamper IN OUT alter-command STEP | inject-garbage | inject-orphan\n");
    return 2;
  }
  const std::string mode = argv[3];
  lcm::LogFile in(argv[1], "r");
  lcm::LogFile out(argv[2], "w");
  if (!in.good() || !out.good()) {
    std::fprintf(stderr, "replay_log_tamper: cannot open %s or %s\n", argv[1], argv[2]);
    return 1;
  }
  const long step = mode == "alter-command" && argc > 4 ? std::stol(argv[4]) : -1;
  std::mt19937 rng(11);
  int64_t num = 0, disturbed_episode = 0;
  long altered = 0, events = 0;
  bool orphaned = false;
  for (const lcm::LogEvent* ev; (ev = in.readNextEvent()) != nullptr;) {
    ++events;
    if (ev->channel.size() >= 14 && ev->channel.substr(ev->channel.size() - 14) == "EPISODE_CONFIG") {
      pidlab::lcmt_episode_config c;
      if (c.decode(ev->data, 0, ev->datalen) > 0 && c.disturbance_kind != "none")
        disturbed_episode = c.episode_id;
    }
    pidlab::lcmt_control_command m;
    if (step >= 0 && m.decode(ev->data, 0, ev->datalen) > 0 && m.episode_id == disturbed_episode &&
        m.step == step) {
      m.u = std::nextafter(m.u, HUGE_VAL);
      std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent copy = *ev;
      copy.data = buf.data();
      Put(&out, copy, &num);
      ++altered;
      continue;
    }
    pidlab::lcmt_trajectory_chunk chunk;
    if (step >= 0 && chunk.decode(ev->data, 0, ev->datalen) == ev->datalen &&
        chunk.episode_id == disturbed_episode && chunk.step <= step && step < chunk.step + chunk.count &&
        static_cast<std::size_t>(step - chunk.step) < chunk.u.size()) {
      double& u = chunk.u[static_cast<std::size_t>(step - chunk.step)];
      u = std::nextafter(u, HUGE_VAL);
      std::vector<uint8_t> buf(static_cast<std::size_t>(chunk.getEncodedSize()));
      chunk.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent copy = *ev;
      copy.data = buf.data();
      Put(&out, copy, &num);
      ++altered;
      continue;
    }
    Put(&out, *ev, &num);
    pidlab::lcmt_plant_output output;
    if (mode == "inject-orphan" && !orphaned && output.decode(ev->data, 0, ev->datalen) == ev->datalen) {
      for (int64_t id : {987654321, 987654322, 987654323}) {
        output.episode_id = id;
        std::vector<uint8_t> buf(static_cast<std::size_t>(output.getEncodedSize()));
        output.encode(buf.data(), 0, static_cast<int>(buf.size()));
        PutBytes(&out, ev->channel, buf, &num);
      }
      orphaned = true;
    }
    if (mode == "inject-garbage" && events % 50 == 0) {
      std::vector<uint8_t> junk(40);
      for (auto& b : junk) b = static_cast<uint8_t>(rng());
      PutBytes(&out, "STRANGER_POSE", junk, &num);
      PutBytes(&out, "PIDLAB_CONTROL", junk, &num);               // unknown fingerprint
      PutBytes(&out, "PIDLAB_PLANT_OUTPUT", {0x00, 0x01}, &num);  // too short to be anything
    }
  }
  if (mode == "inject-orphan" && !orphaned) {
    std::fprintf(stderr, "replay_log_tamper: no plant output to forge an orphan from\n");
    return 1;
  }
  if (mode == "alter-command" && altered == 0) {
    std::fprintf(stderr, "replay_log_tamper: no command of step %ld found\n", step);
    return 1;
  }
  return 0;
}
