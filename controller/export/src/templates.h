#pragma once
// The generated C's text, with @NAME@ placeholders (export.cc fills them).

namespace pidlab::controller_export::internal {

/// Floating point (double, float): @COMMENT@, @REAL@ in the header, @CONFIG@
/// (the initializer's lines) in the source.
extern const char* const kRealHeader;
extern const char* const kRealSource;
/// Fixed point (q31, q15): @COMMENT@ and the scalings (fixed_point.cc).
extern const char* const kFixedHeader;
extern const char* const kFixedSource;
// The relay autotune (double, with pidlab_pid.h): pidlab_relay.h, pidlab_relay.c.
extern const char* const kRelayHeader;
extern const char* const kRelaySource;
// The relay autotune in fixed point (q31, q15, with the fixed pidlab_pid.h).
extern const char* const kRelayFixedHeader;
extern const char* const kRelayFixedSource;

}  // namespace pidlab::controller_export::internal

#include <string>

#include "pidlab/controller_export/export.h"

namespace pidlab::controller_export::internal {

/// The fixed-point module (q31, q15): the scalings, the range analysis and
/// the text. `comment` is the header comment's common part.
GeneratedCode GenerateFixed(const Options& options, const Controller& controller, const std::string& comment);
/// Its grids (export.h's FixedPointScale).
FixedScale Scales(const Options& options, const Controller& controller);

}  // namespace pidlab::controller_export::internal
