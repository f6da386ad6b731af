#pragma once
// The one error type that crosses pidlab's library boundaries: a code the
// caller acts on and a one-line message naming the value, the field or the
// process. Front ends choose exit codes from the code in one place
// (tools/cli_common.h, Require: kInvalidInput exits 2, every other code 1); libraries never throw across their edge
// for a user's mistake or a failed run.

#include <string>
#include <utility>

namespace pidlab {

enum class StatusCode {
  kOk,
  /// Something the user gave is invalid: a value, a file, a combination.
  kInvalidInput,
  /// A backend that runs the loop (the trio, a log) failed: not the user's input.
  kRunnerFailed,
  /// The loop is not strictly stable where a stable one was required.
  kUnstable,
  /// A file could not be read or written whole (a full disk, an I/O error):
  /// the message names the path and the system's words for the cause.
  kIoFailed,
};

class Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }
  static Status InvalidInput(std::string message) { return {StatusCode::kInvalidInput, std::move(message)}; }
  static Status RunnerFailed(std::string message) { return {StatusCode::kRunnerFailed, std::move(message)}; }
  static Status IoFailed(std::string message) { return {StatusCode::kIoFailed, std::move(message)}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

/// "ok", "invalid input", "runner failed", "unstable", "i/o failed".
inline const char* ToString(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "ok";
    case StatusCode::kInvalidInput:
      return "invalid input";
    case StatusCode::kRunnerFailed:
      return "runner failed";
    case StatusCode::kUnstable:
      return "unstable";
    case StatusCode::kIoFailed:
      return "i/o failed";
  }
  return "unknown";
}

}  // namespace pidlab
