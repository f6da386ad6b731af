#pragma once
// Checks a datagram's wire layout before the generated LCM decoder sees it.
// The decoders of LCM 1.3.1 trust the array lengths declared in a message: a
// hostile or corrupt length of 2^28 makes them zero-fill gigabytes and then
// overflow an int (a crash from one datagram). Every variable-length field is
// bounded here against the bytes actually present and the protocol's own
// limits (protocol.h), so decoding only ever runs on a well-formed payload.

#include <cstdint>
#include <pidlab/lcmt_episode_config_layout.hpp>
#include <string>

namespace pidlab::transport {

/// Largest plant polynomial a configuration may carry (coefficients).
inline constexpr int kMaxPolynomialCoefficients = 64;
/// Longest string field, bytes (plant names, options, roles, messages).
inline constexpr int kMaxStringBytes = 4096;

/// Which version of lcmt_episode_config a fingerprint names: kEpisodeConfigVersion
/// for the current type, 1..kEpisodeConfigVersion - 1 for its frozen copies
/// lcmt_episode_config_v1.. (generated from the "//@frozen" lines of
/// lcmtypes/lcmt_episode_config.lcm: each holds the fields before an append),
/// 0 for any other fingerprint.
inline constexpr int kEpisodeConfigVersion = lcm_layout::lcmt_episode_config::kVersions;
int EpisodeConfigVersion(int64_t fingerprint);

/// True if `data` (size bytes, fingerprint first) has the layout of the
/// pidlab message whose fingerprint is `fingerprint`, with every string and
/// array length within the payload and the protocol's limits. Messages
/// without variable-length fields are only checked for their fingerprint.
/// False for an unknown fingerprint.
bool WireLayoutOk(int64_t fingerprint, const void* data, int size);

/// The wire text of a stranger, safe to print: bytes outside printable ASCII
/// escaped as \xNN, cut to max_bytes with "..." appended.
std::string EscapeWireText(const std::string& text, std::size_t max_bytes = 200);

}  // namespace pidlab::transport
