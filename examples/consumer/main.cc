// Uses an installed pidlab (find_package(pidlab CONFIG), pidlab::tuner):
// evaluates the paper's double integrator 1/s^2 with the paper's
// Nelder-Mead gains (Table II), then tunes the oscillator 1/(s^2+1).
// Prints every number with 17 significant digits, so that they can be
// compared bit for bit with `pidlab evaluate --json` and `pidlab tune --json`.

#include <cstdio>
#include <string>

#include "pidlab/evaluation/evaluation.h"
#include "pidlab/transport/protocol.h"
#include "pidlab/tune/tune.h"

int main() {
  // 1. The plant by name, the gains of Table II, the paper's loop
  //    (continuous, ts = 0.05 s, n = 25 s).
  pidlab::Plant plant;
  if (const pidlab::Status st =
          pidlab::MakePlant("double_integrator", pidlab::StepperMotorParameters{}, &plant);
      !st.ok()) {
    std::fprintf(stderr, "consumer: %s\n", st.message().c_str());
    return 2;
  }
  const pidlab::PidGains paper_nm{29.6558, 0.4977, 28.3216};
  pidlab::evaluation::Evaluation evaluation;
  if (const pidlab::Status st =
          pidlab::evaluation::Evaluate(plant, paper_nm, pidlab::evaluation::LoopOptions{},
                                       pidlab::evaluation::EvaluateOptions{}, &evaluation);
      !st.ok()) {
    std::fprintf(stderr, "consumer: %s\n", st.message().c_str());
    return 2;
  }
  std::printf("evaluate %s iae=%.17g overshoot_pct=%.17g stable=%d\n", plant.name.c_str(), evaluation.iae,
              evaluation.step.overshoot_pct, evaluation.stability.stable ? 1 : 0);

  // 2. A plant from its coefficients, tuned by the default multi-start (at
  //    most 400 evaluations: 200 Sobol' design points, then 16 Nelder-Mead
  //    polishes), then cross-checked by Ceres.
  pidlab::Plant oscillator;
  if (const pidlab::Status st = pidlab::MakeCustomPlant({1.0}, {1.0, 0.0, 1.0}, &oscillator); !st.ok()) {
    std::fprintf(stderr, "consumer: %s\n", st.message().c_str());
    return 2;
  }
  pidlab::tune::TuneOptions options;
  options.max_evaluations = 400;
  pidlab::tune::TuneSummary summary;
  if (const pidlab::Status st = pidlab::tune::Tune(oscillator, options, &summary); !st.ok()) {
    std::fprintf(stderr, "consumer: %s\n", st.message().c_str());
    return 2;
  }
  std::printf("tune kp=%.17g ki=%.17g kd=%.17g objective=%.17g\n", summary.gains.kp, summary.gains.ki,
              summary.gains.kd, summary.objective);
  std::printf("%s\n", summary.BriefReport().c_str());
  // Over a trio (pidlab launch), pidlab::episode_client::EpisodeClient is the SampledRunner
  // to pass to Evaluate and Tune; its default URL:
  std::printf("trio url %s\n", pidlab::transport::kDefaultLcmUrl);
  return summary.stable ? 0 : 1;
}
