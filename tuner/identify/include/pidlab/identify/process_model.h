#pragma once
// The process models live with the plants (pidlab/plant_sim/process_model.h),
// where the Monte Carlo draws of an identified model can reach them; their
// names are brought into pidlab::identify here, where they were first.

#include "pidlab/plant_sim/process_model.h"

namespace pidlab::identify {

using pidlab::plant_sim::ModelFromValues;
using pidlab::plant_sim::ParameterNames;
using pidlab::plant_sim::ParameterValues;
using pidlab::plant_sim::Parse;
using pidlab::plant_sim::ProcessModel;
using pidlab::plant_sim::ProcessModelKind;
using pidlab::plant_sim::ProcessModelKindNames;
using pidlab::plant_sim::ToString;

}  // namespace pidlab::identify
