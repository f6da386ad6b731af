// pidlab linearize: the transfer function of the nonlinear stepper's
// linearisation at the holding point, by automatic differentiation.

#include <iomanip>
#include <iostream>
#include <limits>

#include "cli_common.h"
#include "cli_spec.h"
#include "commands.h"
#include "pidlab/plant_sim/stepper_nonlinear.h"
#include "pidlab/tune/problem.h"

using pidlab::spec::NameStyle;

namespace pidlab::cli {
namespace {

struct LinearizeCommand {
  SpecFlags flags;
  bool json = false;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Linearise a nonlinear plant at its operating point (stepper_nonlinear: both phases at I_o, theta = "
        "lambda/2, at rest, no load) by automatic differentiation of the model, and print u -> y as "
        "{\"num\": [...], \"den\": [...]} in descending powers of s with a monic denominator. With Table I "
        "and the default --input-scale this is eq. (3) (docs/stepper.md).");
    flags.Register(app, spec::PlantSpec{}, /*spec_file=*/false);
    app->add_flag("--json", json, "print one JSON object {num, den, plant, eq3} instead of text");
    return [this] { return Run(); };
  }

  int Run() {
    spec::PlantSpec plant;
    flags.Apply(&plant, nullptr);
    if (plant.plant != "stepper_nonlinear")
      throw BadInput("--plant " + Quote(plant.plant) +
                     " is not a nonlinear plant (expected stepper_nonlinear)");
    std::string error;
    NonlinearStepperOptions o;
    Require(pidlab::tune::BuildNonlinearStepper(plant, NameStyle::kFlag, &o));
    StepperLinearization lin;
    if (const Status st = LinearizeStepper(o, &lin); !st.ok()) throw BadInput(st.message());
    const TransferFunction eq3 = StepperMotorTransferFunction(o.motor);
    if (json) {
      const nlohmann::json j = results::LinearizeJson(lin.tf, eq3, o.InputScale());
      std::cout << std::setprecision(std::numeric_limits<double>::max_digits10) << j.dump() << "\n";
    } else {
      std::cout << std::setprecision(10) << "linearisation  G(s) = " << lin.tf.ToString() << "\n"
                << "eq. (3)        G(s) = " << eq3.ToString() << "\n"
                << "input scale g  " << o.InputScale() << " (phi = theta0 + g u)\n";
    }
    return 0;
  }
};

}  // namespace
std::function<int()> RegisterLinearize(CLI::App* app) { return RegisterCommand<LinearizeCommand>(app); }

}  // namespace pidlab::cli
