#include "pidlab/report/trio_episode.h"

#include <fstream>
#include <sstream>

#include "pidlab/episode_client/episode_client.h"
#include "pidlab/launcher/launcher.h"

using pidlab::episode_client::EpisodeClient;
using pidlab::episode_client::EpisodeClientOptions;

namespace pidlab::report {

bool RunTrioEpisode(const TrioEpisodeOptions& options, const Plant& plant, const PidGains& gains, double dt_s,
                    double horizon_s, Metrics* metrics, std::string* note) {
  std::string error;
  if (options.isolated) {
    if (const Status st = launcher::EnterIsolatedNetwork(); !st.ok()) {
      *note = st.message();
      return false;
    }
  }
  auto log = std::make_shared<std::ofstream>(options.log_path, std::ios::app);
  launcher::LaunchOptions lo;
  lo.bin_dir = options.bin_dir;
  lo.stderr_path = options.log_path;
  launcher::Launcher trio(lo, [log](const std::string& line) {
    *log << "pidlab launch: " << line << "\n" << std::flush;
  });
  if (trio.Start(nullptr, &error) != launcher::LaunchStatus::kReady) {
    *note = "the trio did not start: " + error + " (see " + options.log_path + ")";
    return false;
  }
  EpisodeClientOptions co;
  co.lcm_url = trio.lcm_url();
  EpisodeClient client(co);
  evaluation::LoopOptions loop;
  loop.loop = evaluation::LoopKind::kSampled;
  loop.dt_s = dt_s;
  loop.horizon_s = horizon_s;
  evaluation::Evaluation ev;
  if (const Status st = evaluation::Evaluate(plant, gains, loop, evaluation::EvaluateOptions{}, &ev, client.AsRunner()); !st.ok()) {
    *note = "the trio episode failed: " + st.message() + " (see " + options.log_path + ")";
    return false;
  }
  trio.Stop();
  FillFromEvaluation(ev, metrics);
  std::ostringstream os;
  os.precision(17);
  os << "one episode over the LCM trio (pidlab-plant, pidlab-controller, pidlab-disturbance) started by the "
        "launcher library in a private network namespace, driven by the tuner's episode client: the sampled "
        "loop at dt "
     << dt_s << " s for " << horizon_s << " s";
  *note = os.str();
  return true;
}

}  // namespace pidlab::report
