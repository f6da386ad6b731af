// pidlab serve: the tuning workbench in the browser (docs/workbench.md).

#include <csignal>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/server/assets.h"
#include "pidlab/server/server.h"
#include "serve_requests.h"

namespace pidlab::cli {
namespace {

server::Server* g_server = nullptr;
extern "C" void StopOnSignal(int) {
  if (g_server) g_server->Stop();
}

struct ServeCommand {
  server::ServerOptions options;
  std::string token;

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Serve the tuning workbench: an HTTP and WebSocket server (Boost.Beast) with the page, answering "
        "evaluate requests with the JSON of 'pidlab evaluate --json' (docs/workbench.md). Open the printed "
        "URL.");
    app->add_option("--port", options.port, "TCP port (0: any free port, printed)")->capture_default_str();
    app->add_option("--bind", options.bind,
                    "address to listen on; anything but loopback requires the token, printed once")
        ->capture_default_str();
    return [this] { return Run(); };
  }

  int Run() {
    if (!server::IsLoopback(options.bind)) options.token = RandomToken();
    std::string error;
    if (!options.IsValid(&error)) throw BadInput(error);
    server::Server s(options, server::ConnectionHandler(AnswerWorkbenchRequest), server::WorkbenchAssets());
    if (!s.Start(&error)) throw BadInput(error);
    const std::string host =
        options.bind.find(':') != std::string::npos ? "[" + options.bind + "]" : options.bind;
    std::cout << "pidlab serve: http://" << host << ":" << s.port() << "/"
              << (options.token.empty() ? "" : "?token=" + options.token) << std::endl;
    g_server = &s;
    std::signal(SIGINT, StopOnSignal);
    std::signal(SIGTERM, StopOnSignal);
    s.Run();
    g_server = nullptr;
    std::cerr << "pidlab serve: stopped\n";
    return 0;
  }

  // 32 hex digits from /dev/urandom.
  static std::string RandomToken() {
    std::ifstream in("/dev/urandom", std::ios::binary);
    unsigned char bytes[16] = {};
    in.read(reinterpret_cast<char*>(bytes), sizeof bytes);
    if (!in) throw std::runtime_error("cannot read /dev/urandom for the token");
    static const char* hex = "0123456789abcdef";
    std::string t;
    for (unsigned char b : bytes) t += hex[b >> 4], t += hex[b & 15];
    return t;
  }
};

}  // namespace

std::function<int()> RegisterServe(CLI::App* app) {
  auto command = std::make_shared<ServeCommand>();
  auto action = command->Register(app);
  return [command, action] { return action(); };
}

}  // namespace pidlab::cli
