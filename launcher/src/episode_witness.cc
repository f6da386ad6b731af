#include "pidlab/launcher/episode_witness.h"

#include <lcm/eventlog.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <pidlab/lcmt_episode_summary.hpp>
#include <string>
#include <vector>

#include "pidlab/transport/protocol.h"

namespace pidlab::launcher {

EpisodeWitness::EpisodeWitness(transport::Transport* transport, std::size_t max_episodes)
    : max_episodes_(std::max<std::size_t>(max_episodes, 1)) {
  transport->Subscribe<pidlab::lcmt_episode_config>(
      transport::kEpisodeConfigChannel, [this](const pidlab::lcmt_episode_config& m) { OnConfig(m); });
  transport->Subscribe<pidlab::lcmt_episode_summary>(
      transport::kSummaryChannel, [this](const pidlab::lcmt_episode_summary& m) { OnEnded(m.episode_id); });
}

const pidlab::lcmt_episode_config* EpisodeWitness::Config(int64_t episode_id) const {
  const auto it = configs_.find(episode_id);
  return it == configs_.end() ? nullptr : &it->second;
}

void EpisodeWitness::OnConfig(const pidlab::lcmt_episode_config& config) {
  // The first copy: the client repeats it (restamped) until acknowledged.
  if (config.episode_id == 0 || !configs_.emplace(config.episode_id, config).second) return;
  config_order_.push_back(config.episode_id);
  if (config_order_.size() > max_episodes_) {
    configs_.erase(config_order_.front());
    config_order_.pop_front();
  }
}

void EpisodeWitness::OnEnded(int64_t episode_id) {
  // The plant repeats its summary (5 copies, 0.1 s apart).
  if (episode_id == 0 || !ended_.insert(episode_id).second) return;
  ended_order_.push_back(episode_id);
  if (ended_order_.size() > max_episodes_) {
    ended_.erase(ended_order_.front());
    ended_order_.pop_front();
  }
}

Status WriteConfigLog(std::vector<pidlab::lcmt_episode_config> configs, const std::string& channel,
                      const std::optional<transport::AuthKey>& key, const std::string& file) {
  std::stable_sort(configs.begin(), configs.end(),
                   [](const auto& a, const auto& b) { return a.utime < b.utime; });
  lcm_eventlog_t* log = lcm_eventlog_create(file.c_str(), "w");
  if (!log) return Status::IoFailed("cannot write " + file);
  bool ok = true;
  std::string name = channel;
  for (const pidlab::lcmt_episode_config& config : configs) {
    const int size = config.getEncodedSize();
    std::vector<uint8_t> data(static_cast<std::size_t>(size) + (key ? transport::kAuthTagBytes : 0));
    config.encode(data.data(), 0, size);
    if (key) {
      const auto tag = transport::AuthTag(*key, channel, data.data(), static_cast<std::size_t>(size));
      std::copy(tag.begin(), tag.end(), data.begin() + size);
    }
    lcm_eventlog_event_t ev{};
    ev.timestamp = config.utime;
    ev.channellen = static_cast<int32_t>(name.size());
    ev.datalen = static_cast<int32_t>(data.size());
    ev.channel = name.data();
    ev.data = data.data();
    ok = ok && lcm_eventlog_write_event(log, &ev) == 0;
  }
  lcm_eventlog_destroy(log);
  if (ok) return Status::Ok();
  std::remove(file.c_str());
  return Status::IoFailed("cannot write " + file);
}

std::string EpisodeList(const std::vector<int64_t>& ids, std::size_t shown) {
  shown = std::max<std::size_t>(shown, 1);
  std::string s;
  const std::size_t listed = ids.size() > shown ? shown : ids.size();
  for (std::size_t i = 0; i < listed; ++i) {
    const bool last = i + 1 == listed && ids.size() <= shown;
    s += (i == 0 ? "" : last ? " and " : ", ") + std::to_string(ids[i]);
  }
  if (ids.size() > shown) s += " and " + std::to_string(ids.size() - shown) + " more";
  return s;
}

}  // namespace pidlab::launcher
