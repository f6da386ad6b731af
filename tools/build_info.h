#pragma once
// What `pidlab --version` and `pidlab version` print. The definitions are
// generated at build time (cmake/PidlabBuildInfo.cmake), so a new commit
// recompiles one small file.

namespace pidlab::cli {

/// The project version, CMake's PROJECT_VERSION ("0.2.0").
const char* Version();

/// The git commit the tree was built from, abbreviated to 12 hex digits, with
/// ", modified" when a tracked file differed from it; "unknown" for a tree
/// outside git.
const char* GitCommit();

}  // namespace pidlab::cli
