// pidlab evaluate: IAE, stability and step metrics of one gain set.

#include <iostream>

#include "cli_common.h"

namespace pidlab::cli {
namespace {

struct EvaluateCommand {
  PlantFlags plant;
  LoopFlags loop;
  std::string gains;
  bool json = false;
  std::string samples_csv;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Evaluate one PID gain set on a plant: the paper's IAE (eq. 4) and other error sums, closed-loop "
        "poles and strict stability, MATLAB-stepinfo rise/overshoot/settling of the unit-step response.");
    plant.Register(app);
    loop.Register(app);
    app->add_option("--gains", gains, "KP,KI,KD (each finite and >= 0)")->required();
    app->add_flag("--json", json, "print one JSON object instead of the table");
    app->add_option("--samples-csv", samples_csv, "write t,r,y,e,n at the sample times to this CSV file");
    return [this] { return Run(); };
  }

  int Run() {
    const Plant p = plant.Build();
    const PidGains g = ParseGains(gains);
    const LoopOptions options = loop.Build();
    Evaluation ev;
    std::string error;
    if (!Evaluate(p, g, options, EvaluateOptions{}, &ev, &error)) throw BadInput(error);
    if (!samples_csv.empty()) WriteSamplesCsv(ev, samples_csv);
    if (json) {
      std::cout << ToJson(ev).dump() << "\n";
    } else {
      std::cout << FormatEvaluation(ev);
    }
    return 0;
  }
};

EvaluateCommand command;
const CommandRegistrar registrar("evaluate", "evaluate one gain set (IAE, poles, step metrics)",
                                 [](CLI::App* sub) { return command.Register(sub); });

}  // namespace
}  // namespace pidlab::cli
