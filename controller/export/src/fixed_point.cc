// The fixed-point module (q31, q15).

#include <stdexcept>

#include "templates.h"

namespace pidlab::controller_export::internal {

GeneratedCode GenerateFixed(const Options& options, const Controller&, const std::string&) {
  throw std::invalid_argument("--scalar " + ToString(options.scalar) + " is not implemented yet");
}

}  // namespace pidlab::controller_export::internal
