#pragma once
// The pieces `pidlab export` and the workbench's export request share: the
// controller of a spec and the header comment's plant and spec text
// (docs/export.md).

#include <nlohmann/json.hpp>
#include <string>

#include "pidlab/controller_export/export.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/spec/status.h"

namespace pidlab::cli {

/// The discrete PID of the spec's gains and loop: LoopGains, the PID's
/// options at dt, the setpoint weights. False with *error (one line, the
/// field named in `style`) for a spec without gains or with bad values.
bool ExportController(const spec::EvaluateSpec& s, spec::NameStyle style, controller_export::Controller* c,
                      std::string* error);

/// One line naming the plant, for the header comment.
std::string DescribePlant(const spec::PlantSpec& p);

/// The spec's JSON, one field a line (the header comment's form).
std::string SpecText(const nlohmann::json& j);

}  // namespace pidlab::cli
