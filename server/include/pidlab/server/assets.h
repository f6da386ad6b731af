#pragma once
// The workbench page (server/www/), built into the library.

#include <vector>

#include "pidlab/server/server.h"

namespace pidlab::server {

/// index.html at "/", app.js at "/app.js".
std::vector<Asset> WorkbenchAssets();

}  // namespace pidlab::server
