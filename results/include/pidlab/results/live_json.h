#pragma once
// The live_status object of the live scope (`pidlab serve --lcm-url`,
// docs/live.md): the episodes of the trios watched, their tunings, the
// roles' health and the pacing, as the page reads them.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/monitor/live_scope.h"

namespace pidlab::results {

/// The live_status object of `view`: health is the first trio's, and with
/// several trios "trios" lists each one's URL and health.
nlohmann::json LiveStatusJson(const monitor::LiveView& view, const std::string& lcm_url,
                              const std::string& channel_prefix, const int64_t* selected_episode_id,
                              long dropped_frames);

}  // namespace pidlab::results
