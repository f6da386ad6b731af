#pragma once
// The tests' view of pidlab::Status (spec/status.h), the one error type
// across the libraries' edges.

#include <gtest/gtest.h>

#include <string>

#include "pidlab/spec/status.h"

namespace pidlab {

/// ASSERT_TRUE(IsOk(status)): a failure prints the status's code and message.
inline ::testing::AssertionResult IsOk(const Status& s) {
  if (s.ok()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << ToString(s.code()) << ": " << s.message();
}

/// s.ok(), with its message in *message (when not null): for a test that
/// checks what a refusal says.
inline bool OkInto(const Status& s, std::string* message) {
  if (message) *message = s.message();
  return s.ok();
}

}  // namespace pidlab
