#pragma once
// The requests of the workbench page (docs/workbench.md, "The protocol"),
// answered with the code of the command line: evaluate (with the plot
// series), fields, paper_designs. `pidlab serve` passes Answer to the server.

#include <memory>
#include <nlohmann/json.hpp>

#include "pidlab/server/server.h"

namespace pidlab::cli {

class LiveService;

/// One request object of the page, with the WebSocket connection it came on
/// (null over HTTP); 400 with one line for a bad one. The live requests go
/// to `live` (null: `pidlab serve` without --lcm-url).
server::Reply AnswerWorkbenchRequest(const nlohmann::json& request,
                                     const std::shared_ptr<server::Connection>& connection,
                                     LiveService* live);

/// tune (serve_tune.cc): starts the tuning of request["spec"] on a thread;
/// no reply now, its progress and result are posted on `connection`.
server::Reply AnswerTune(const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection);
/// tune_cancel: stops the connection's running tuning at its next iteration.
server::Reply AnswerTuneCancel(const std::shared_ptr<server::Connection>& connection);

/// The paper's published gains (Tables II-VI, the report's built-in
/// data/paper_tables.csv): [{table, plant, method, disturbance_amplitude,
/// gains: [kp, ki, kd]}].
nlohmann::json PaperDesigns();

}  // namespace pidlab::cli
