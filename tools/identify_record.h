#pragma once
// The record `pidlab identify` fits, read the same way for the command line
// and the page's identify request: a CSV's columns t, u, y, or one episode
// of a trio's log (the plant's input u + n held over each step, the
// measured y).

#include <string>

#include "pidlab/identify/identify.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/spec/status.h"

namespace pidlab::cli {

/// The CSV at `path` (identify::ReadCsvData, whose refusals name the
/// file), with the record's rules (identify::CheckData) checked so that a
/// refusal names the row: kInvalidInput "SOURCE: why", SOURCE how the
/// caller names the record.
Status ReadCsvRecord(const std::string& path, const std::string& source, identify::IdentifyData* data);

/// Whether the episode's plant input u + n changes over the episode (an
/// evaluate run logs its undisturbed twin too, whose input is constant).
bool EpisodeInputVaries(const replay::Episode& e);

/// Step k of a complete episode: y_k measured, then u_k + n_k held over
/// [k dt, (k + 1) dt).
identify::IdentifyData EpisodeRecord(const replay::Episode& e);

}  // namespace pidlab::cli
