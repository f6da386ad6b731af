// pidlab version (and pidlab --version): the project version and the git
// commit the binary was built from (tools/build_info.h).

#include <iostream>
#include <string>

#include "build_info.h"
#include "commands.h"

namespace pidlab::cli {

std::string VersionLine() { return std::string("pidlab ") + Version() + " (commit " + GitCommit() + ")"; }

std::function<int()> RegisterVersion(CLI::App* app) {
  app->description(
      "Print the version (CMake's project version) and the git commit this pidlab was built from, with "
      "', modified' when a tracked file differed from it, 'unknown' for a tree outside git; the same as "
      "'pidlab --version'.");
  return [] {
    std::cout << VersionLine() << "\n";
    return 0;
  };
}

}  // namespace pidlab::cli
