// pidlab serve: the tuning workbench in the browser (docs/workbench.md).

#include <sodium.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "cli_common.h"
#include "commands.h"
#include "pidlab/episode_client/episode_pool.h"
#include "pidlab/server/assets.h"
#include "pidlab/server/server.h"
#include "pidlab/spec/field.h"
#include "serve_live.h"
#include "serve_logs.h"
#include "serve_requests.h"

namespace pidlab::cli {
namespace {

server::Server* g_server = nullptr;
extern "C" void StopOnSignal(int) {
  if (g_server) g_server->Stop();
}

constexpr std::size_t kMaxWatchedTrios = 64;  // pidlab launch --trios' bound

struct ServeCommand {
  server::ServerOptions options;
  std::string token;
  std::string log_dir = ".";
  long max_upload_mb = 64;
  LcmFlags lcm;  // --lcm-url, --channel-prefix, --auth-key: the live scope (docs/live.md)

  std::function<int()> Register(CLI::App* app) {
    app->description(
        "Serve the tuning workbench: an HTTP and WebSocket server (Boost.Beast) with the page, answering "
        "evaluate requests with the JSON of 'pidlab evaluate --json' (docs/workbench.md). Open the printed "
        "URL. With --lcm-url it also watches a running trio: the live scope (docs/live.md).");
    app->add_option("--port", options.port, "TCP port (0: any free port, printed)")->capture_default_str();
    app->add_option("--bind", options.bind,
                    "address to listen on; anything but loopback requires the token, printed once")
        ->capture_default_str();
    // The Logs tab (serve_logs.h).
    app->add_option("--log-dir", log_dir,
                    "the directory log_open paths are relative to (default: the current one)");
    app->add_option("--max-upload-mb", max_upload_mb, "largest uploaded log, MiB (1..4096)")
        ->capture_default_str();
    app->add_option("--body-timeout", options.body_timeout_s,
                    "seconds a request or upload body may take after its header (0.1..3600): a body that "
                    "trickles past them is answered 408 and its connection closed")
        ->check(FiniteNumber())
        ->capture_default_str();
    app->add_option("--lcm-url", lcm.lcm_url,
                    "watch the trio on this LCM URL, or the trios of several, comma-separated (pidlab launch "
                    "--trios K: $PIDLAB_LCM_URLS): the live scope, episodes on demand on the first "
                    "(docs/live.md); without it the live requests answer 400");
    app->add_option(
        "--channel-prefix", lcm.channel_prefix,
        "with --lcm-url: the trio's channel prefix (default $PIDLAB_CHANNEL_PREFIX, else PIDLAB_)");
    app->add_option("--auth-key", lcm.auth_key_file,
                    "with --lcm-url: check every message's MAC with the key in this file, and sign the "
                    "episodes run on the trio (docs/security.md; default $PIDLAB_AUTH_KEY_FILE)");
    return [this] { return Run(); };
  }

  int Run() {
    if (!server::IsLoopback(options.bind)) options.token = RandomToken();
    if (!(options.body_timeout_s >= 0.1 && options.body_timeout_s <= 3600))
      throw BadInput("--body-timeout " + spec::FormatNumber(options.body_timeout_s) +
                     " must be in 0.1..3600 s");
    std::string error;
    if (!options.IsValid(&error)) throw BadInput(error);
    std::unique_ptr<LogStore> logs = ServedLogs();
    std::unique_ptr<LiveService> live = StartLive();
    std::atomic<LiveService*> live_requests{nullptr};  // the live requests' service while the server runs
    server::Server s(
        options,
        [&live_requests](const nlohmann::json& request,
                         const std::shared_ptr<server::Connection>& connection) {
          return AnswerWorkbenchRequest(request, connection, live_requests.load());
        },
        server::WorkbenchAssets());
    s.SetUploadHandler(
        [&logs](const std::string& name, const std::string& body) { return logs->Upload(name, body); });
    if (const Status st = s.Start(); !st.ok()) throw BadInput(st.message());
    live_requests = live.get();
    const std::string host =
        options.bind.find(':') != std::string::npos ? "[" + options.bind + "]" : options.bind;
    std::cout << "pidlab serve: http://" << host << ":" << s.port() << "/"
              << (options.token.empty() ? "" : "?token=" + options.token) << std::endl;
    g_server = &s;
    std::signal(SIGINT, StopOnSignal);
    std::signal(SIGTERM, StopOnSignal);
    s.Run();
    // The live threads post to the server's connections: they stop (and a
    // run_on_trio episode ends) while the server still exists.
    live_requests = nullptr;
    live.reset();
    g_server = nullptr;
    ServeLogs(nullptr);
    std::cerr << "pidlab serve: stopped\n";
    return 0;
  }

  // --log-dir and --max-upload-mb checked; the store of the Logs tab.
  std::unique_ptr<LogStore> ServedLogs() {
    std::error_code ec;
    if (!std::filesystem::is_directory(log_dir, ec))
      throw BadInput("--log-dir " + Quote(log_dir) + " is not a directory");
    if (max_upload_mb < 1 || max_upload_mb > 4096)
      throw BadInput("--max-upload-mb " + std::to_string(max_upload_mb) + " must be in 1..4096");
    options.max_upload_bytes = static_cast<std::size_t>(max_upload_mb) * 1024 * 1024;
    auto store = std::make_unique<LogStore>(log_dir);
    ServeLogs(store.get());
    return store;
  }

  // The live scope on the trio of --lcm-url, or null without it.
  std::unique_ptr<LiveService> StartLive() const {
    if (lcm.lcm_url.empty()) {
      if (!lcm.auth_key_file.empty())
        throw BadInput("--auth-key " + Quote(lcm.auth_key_file) + " needs --lcm-url");
      if (!lcm.channel_prefix.empty())
        throw BadInput("--channel-prefix " + Quote(lcm.channel_prefix) + " needs --lcm-url");
      return nullptr;
    }
    const std::vector<std::string> urls = episode_client::SplitUrlList(lcm.lcm_url);
    if (urls.empty() || urls.size() > kMaxWatchedTrios)
      throw BadInput("--lcm-url " + Quote(lcm.lcm_url) + " must name 1 to " +
                     std::to_string(kMaxWatchedTrios) + " URLs");
    std::vector<episode_client::EpisodeClientOptions> trios;
    for (const std::string& url : urls) trios.push_back(lcm.ClientOptions(url));
    std::unique_ptr<LiveService> live;
    try {
      live = std::make_unique<LiveService>(trios, lcm.lcm_url);
    } catch (const std::runtime_error& e) {
      throw BadInput("--lcm-url " + Quote(lcm.lcm_url) + ": " + e.what());
    }
    return live;
  }

  // 32 hex digits: 16 bytes from libsodium's randombytes_buf (the kernel's getrandom).
  static std::string RandomToken() {
    if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised for the token");
    unsigned char bytes[16] = {};
    randombytes_buf(bytes, sizeof bytes);
    char hex[2 * sizeof bytes + 1] = {};
    sodium_bin2hex(hex, sizeof hex, bytes, sizeof bytes);
    return hex;
  }
};

}  // namespace

std::function<int()> RegisterServe(CLI::App* app) { return RegisterCommand<ServeCommand>(app); }

}  // namespace pidlab::cli
