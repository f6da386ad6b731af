#pragma once
// The one description of an episode of the loop: its timing, reference, the
// PID's options (setpoint weights b, c included), the disturbance on the plant
// input and the noise on the measured y. The plant (and its dead time,
// Plant::delay_s) travels beside it.
//
// Both sides of the house embed it, so neither copies the other's fields by
// hand: the evaluation's loop (evaluation::LoopOptions, which adds the loop
// kind and the derivative filter's rules) and the trio's episode
// (transport::EpisodeSpec, which adds the plant, the gains, the episode id and
// the recovery). Assigning one to the other's EpisodeShape copies exactly
// these fields:
//   static_cast<EpisodeShape&>(spec) = loop_options;
// A field added here reaches both, and the message (lcmt_episode_config)
// through transport/src/episode_spec.cc. Each side validates it with its own
// rules (LoopOptions::IsValid, EpisodeSpec::IsValid).

#include "pidlab/controller/pid.h"
#include "pidlab/plant_sim/disturbance.h"

namespace pidlab {

struct EpisodeShape {
  /// Period of the sampled loop (the trio's lockstep period), s. The
  /// continuous loop ignores it; sample_time_s must be a multiple of it.
  double dt_s = 1e-3;
  /// ts of eq. (4): spacing of the error samples, s.
  double sample_time_s = 0.05;
  /// n of eq. (4): last sample time, s; a multiple of sample_time_s.
  double horizon_s = 25.0;
  /// A: size of the reference step r(t) = A for t >= 0 (the paper's unit step
  /// is 1). Every error is e = A - y; step metrics stay relative to the final
  /// value. Finite, nonzero, |A| <= kMaxCoefficientMagnitude.
  double reference = 1.0;
  /// Discrete PID options; their dt_s is taken from dt_s (PidOptionsAt).
  /// pid.derivative_filter_s is the derivative filter tf of both loops for
  /// gains that carry none; pid.setpoint_weight_b and _c the 2-DOF weights.
  PidOptions pid;
  /// n(t), added to the plant input.
  DisturbanceOptions disturbance;
  /// Seeded Gaussian noise on the measured y (sampled loop only): the PID,
  /// the run record and every score see y_k + v_k (docs/spec.md). Its seed
  /// is kept apart from disturbance.seed because a run without the
  /// disturbance (the undisturbed response) keeps the noise.
  MeasurementNoise measurement_noise;
};

}  // namespace pidlab
