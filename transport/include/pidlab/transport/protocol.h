#pragma once
// The trio's wire protocol: channel names and the limits every party keeps.
// The messages are in lcmtypes/ (see lcmtypes/README.md); the roles in
// plant_sim/ and controller/; the client in tuner/episode_client.h.
//
// Lockstep, per step k of an episode:
//   plant       publishes y_k = C x_k                       (PLANT_OUTPUT)
//   controller  answers u_k = PID(r, y_k)                    (CONTROL)
//   plant       waits for u_k and n_k, x_{k+1} = Phi x_k + Gamma (u_k + n_k)
// n does not depend on y: the plant requests it ahead in blocks
// (DISTURBANCE_REQUEST); the disturbance answers with n_k = n(k dt) for a
// block of steps (DISTURBANCE_BLOCK) and never sees y_k. The plant streams its
// trajectory (TRAJECTORY chunks) and answers TRAJECTORY_REQUEST. See
// docs/trio.md for loss recovery.

#include <cstddef>

namespace pidlab::transport {

/// Default LCM URL of a trio (multicast, never leaves the host: ttl=0).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
inline constexpr const char* kDefaultChannelPrefix = "PIDLAB_";
/// LCM's channel names are at most 63 bytes; the longest pidlab channel name is 19.
inline constexpr std::size_t kMaxChannelPrefixBytes = 44;

/// Channel names (without the prefix). See lcmtypes/README.md.
inline constexpr const char* kEpisodeConfigChannel = "EPISODE_CONFIG";
inline constexpr const char* kReadyChannel = "READY";
inline constexpr const char* kPlantOutputChannel = "PLANT_OUTPUT";
inline constexpr const char* kControlChannel = "CONTROL";
inline constexpr const char* kDisturbanceChannel = "DISTURBANCE";  // lcmt_disturbance_sample: old logs only
inline constexpr const char* kDisturbanceRequestChannel = "DISTURBANCE_REQUEST";
inline constexpr const char* kDisturbanceBlockChannel = "DISTURBANCE_BLOCK";
inline constexpr const char* kSummaryChannel = "SUMMARY";
inline constexpr const char* kTrajectoryRequestChannel = "TRAJECTORY_REQUEST";
inline constexpr const char* kTrajectoryChannel = "TRAJECTORY";
inline constexpr const char* kPacingChannel = "PACING";
inline constexpr const char* kTuneProgressChannel = "TUNE_PROGRESS";

/// Samples per lcmt_disturbance_block: one datagram.
inline constexpr long kNoiseBlock = 128;
/// The plant keeps n requested this far ahead of its step.
inline constexpr long kNoiseLookahead = 2 * kNoiseBlock;
/// The disturbance answers at most this many samples per request.
inline constexpr long kMaxNoiseRequest = 8 * kNoiseBlock;
/// Steps per lcmt_trajectory_chunk, and per lcmt_trajectory_request.
inline constexpr long kMaxTrajectoryChunk = 2000;

}  // namespace pidlab::transport
