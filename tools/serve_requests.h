#pragma once
// The requests of the workbench page (docs/workbench.md, "The protocol"),
// answered with the code of the command line: evaluate (with the plot
// series), fields, paper_designs. `pidlab serve` passes Answer to the server.

#include <nlohmann/json.hpp>

#include "pidlab/server/server.h"

namespace pidlab::cli {

/// One request object of the page; 400 with one line for a bad one.
server::Reply AnswerWorkbenchRequest(const nlohmann::json& request);

/// The paper's published gains (Tables II-VI, the report's built-in
/// data/paper_tables.csv): [{table, plant, method, disturbance_amplitude,
/// gains: [kp, ki, kd]}].
nlohmann::json PaperDesigns();

}  // namespace pidlab::cli
