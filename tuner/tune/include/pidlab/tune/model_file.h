#pragma once
// An identified model as a plant: the file `pidlab identify --out` writes
// (results/src/identify_json.cc; docs/identify.md, "The identified model
// as a plant"), read back. Its "transfer_function" (num, den, delay_s) is
// the plant G(s) e^(-s Td); its "model" (the kind), "parameters" (value of
// each, in any order) and "covariance" (ok, message, matrix p x p in the
// order of ParameterNames) become Plant::model, from which the Monte Carlo
// and robust-set draws come (analysis::DrawPlants). A "tf" model also
// carries "poles" and "zeros"; its covariance is read and checked, then
// dropped with a covariance_message saying so, so that its draws perturb the
// transfer function's coefficients (draws from a tf's covariance are not
// built yet).

#include <string>

#include "pidlab/plant_sim/plants.h"
#include "pidlab/spec/status.h"

namespace pidlab::tune {

/// The spec's plant text of a model file: "model:FILE".
inline constexpr const char* kModelPlantPrefix = "model:";
/// The name of a model's plant (Plant::name; the episode carries its
/// num/den/delay as a custom plant's).
inline constexpr const char* kModelPlantName = "model";
/// A model file larger than this is refused.
inline constexpr std::size_t kMaxModelFileBytes = 1u << 20;

/// True when `plant` (a PlantSpec's plant) is "model:FILE"; *path is FILE.
bool IsModelPlant(const std::string& plant, std::string* path = nullptr);

/// Reads the model file at `path` into *plant (name kModelPlantName, tf,
/// delay_s, model). kInvalidInput with one line without the file's name,
/// giving the reason: the file cannot be read or is not JSON, a key is
/// missing or of the wrong type, a number is not finite, the kind is not
/// one of ProcessModelKindNames(), a covariance that is ok is not p x p,
/// the parameters are not a model's (ParametersAreValid), or the transfer
/// function is not a valid, strictly proper plant.
Status ReadModelFile(const std::string& path, Plant* plant);

}  // namespace pidlab::tune
