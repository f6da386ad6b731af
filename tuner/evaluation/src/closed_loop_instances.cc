// The loops of closed_loop.h for double, compiled once here (the header
// declares them extern for every other file).

#include "pidlab/evaluation/closed_loop.h"

namespace pidlab::evaluation {

template Status BuildFilteredClosedLoop<double>(const StateSpace&, const PidGainsT<double>&,
                                                const Disturbance&, ContinuousClosedLoop<double>*, double,
                                                const SetpointWeights&);
template Status BuildContinuousClosedLoop<double>(const StateSpace&, const PidGainsT<double>&,
                                                  const Disturbance&, ContinuousClosedLoop<double>*, double,
                                                  const SetpointWeights&);
template void SampleContinuousLoop<double>(const ContinuousClosedLoop<double>&, const Disturbance&, double,
                                           int, std::vector<double>*);
template PidStatus RunSampledLoop<double>(const DiscretePlant&, const PidGainsT<double>&, const PidOptions&,
                                          const Disturbance&, long, int, std::vector<double>*,
                                          std::vector<SampledStep>*, double, const MeasurementNoise&);

}  // namespace pidlab::evaluation
