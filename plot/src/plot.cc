#include "pidlab/plot/plot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pidlab/io/files.h"

extern char** environ;

namespace pidlab::plot {
namespace {

namespace fs = std::filesystem;

// The largest PNG a figure may be (10000 x 10000 px is the largest size).
constexpr std::size_t kMaxPngBytes = std::size_t{1} << 30;

// Gnuplot double-quoted string: backslash and quote escaped, newline kept as \n.
std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '\\' || c == '"')
      out += '\\', out += c;
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out + "\"";
}

std::string RangeEnd(double v) {
  if (!std::isfinite(v)) return "*";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string StyleClause(const Series& s) {
  std::string clause;
  switch (s.style) {
    case Style::kLines:
      clause = "with lines lw 1.5";
      break;
    case Style::kDashed:
      clause = "with lines lw 1.5 dt 2";
      break;
    case Style::kSteps:
      clause = "with steps lw 1.5";
      break;
    case Style::kPoints:
      clause = "with points pt 7 ps 0.5";
      break;
  }
  if (!s.color.empty()) clause += " lc rgb " + Quote(s.color);
  return clause;
}

// Removes a temporary folder on every return path.
struct TempDir {
  std::string path;
  ~TempDir() {
    if (!path.empty()) {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  }
};

std::string FirstLines(const std::string& path, int max_lines) {
  std::ifstream f(path);
  std::string line, out;
  for (int i = 0; i < max_lines && std::getline(f, line);) {
    if (line.find_first_not_of(" \t^") == std::string::npos) continue;
    if (!out.empty()) out += " | ";
    out += line;
    ++i;
  }
  return out;
}

// The folder for the data files and the script: figure.data_dir (created if
// needed), or a new temporary folder that *temp removes afterwards.
// A new folder under $TMPDIR (else /tmp) that *temp removes afterwards.
bool MakeTempDir(TempDir* temp, std::string* error) {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/pidlab-plot-XXXXXX";
  if (!mkdtemp(pattern.data())) {
    *error = "cannot create a temporary folder: " + std::string(std::strerror(errno));
    return false;
  }
  temp->path = pattern;
  return true;
}

bool MakeDataDir(const Figure& figure, TempDir* temp, std::string* dir, std::string* error) {
  *dir = figure.data_dir;
  std::error_code ec;
  if (dir->empty()) {
    if (!MakeTempDir(temp, error)) return false;
    *dir = temp->path;
  } else if (!fs::create_directories(*dir, ec) && ec) {
    *error = "cannot create data folder " + *dir + ": " + ec.message();
    return false;
  }
  return true;
}

// Writes every series to dir/p<panel>_s<series>.dat; (*files)[p][s] is the
// file name of series s of panel p.
bool WriteDataFiles(const Figure& figure, const std::string& dir,
                    std::vector<std::vector<std::string>>* files, std::string* error) {
  files->assign(figure.panels.size(), {});
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    for (std::size_t s = 0; s < figure.panels[p].series.size(); ++s) {
      const Series& se = figure.panels[p].series[s];
      const std::string name = "p" + std::to_string(p) + "_s" + std::to_string(s) + ".dat";
      std::string text = "# " + se.name + "\n";
      char row[64];
      for (std::size_t i = 0; i < se.x.size(); ++i) {
        const double x = se.x[i], y = se.y[i];
        if (std::isfinite(x) && std::isfinite(y))
          std::snprintf(row, sizeof row, "%.17g %.17g\n", x, y);
        else if (std::isfinite(x))
          std::snprintf(row, sizeof row, "%.17g NaN\n", x);
        else
          std::snprintf(row, sizeof row, "NaN NaN\n");
        text += row;
      }
      if (const Status st = io::WriteFile(dir + "/" + name, text); !st.ok()) {
        *error = st.message();
        return false;
      }
      (*files)[p].push_back(name);
    }
  }
  return true;
}

// The "set ... / plot ..." lines of one panel.
void PanelScript(const Figure& figure, std::size_t p, const std::string& abs_dir,
                 const std::vector<std::string>& files, std::ostream& gp) {
  const Panel& panel = figure.panels[p];
  if (figure.panels.size() > 1)
    gp << "set title " << Quote(panel.title) << "\n";
  else if (!panel.title.empty() && figure.title.empty())
    gp << "set title " << Quote(panel.title) << "\n";
  gp << "set xlabel " << Quote(panel.x_label) << "\n";
  gp << "set ylabel " << Quote(panel.y_label) << "\n";
  gp << "set yrange [" << RangeEnd(panel.y_min) << ":" << RangeEnd(panel.y_max) << "]\n";
  gp << "plot ";
  for (std::size_t s = 0; s < panel.series.size(); ++s) {
    const Series& se = panel.series[s];
    if (s) gp << ", \\\n     ";
    gp << Quote(abs_dir + "/" + files[s]) << " using 1:2 " << StyleClause(se);
    if (se.name.empty())
      gp << " notitle";
    else
      gp << " title " << Quote(se.name);
  }
  gp << "\n";
}

// The gnuplot script drawing `figure` from the data files in abs_dir to abs_out.
std::string GnuplotScript(const Figure& figure, const std::string& abs_dir, const std::string& abs_out,
                          const std::vector<std::vector<std::string>>& files) {
  const std::string size = std::to_string(figure.width_px) + "," + std::to_string(figure.height_px);
  std::ostringstream gp;
  gp << "# pidlab figure: gnuplot " << Quote(abs_dir + "/figure.gp") << "\n";
  gp << "if (strstrt(GPVAL_TERMINALS, \"pngcairo\") > 0) {\n"
     << "  set terminal pngcairo size " << size << " noenhanced font \"sans,10\" linewidth 1\n"
     << "} else {\n"
     << "  set terminal png size " << size << " noenhanced\n"
     << "}\n";
  gp << "set output " << Quote(abs_out) << "\n";
  gp << "set grid\nset key top right opaque box\nset autoscale xfixmin\nset autoscale xfixmax\n";
  const bool multi = figure.panels.size() > 1;
  if (multi) {
    gp << "set multiplot layout " << figure.panels.size() << ",1";
    if (!figure.title.empty()) gp << " title " << Quote(figure.title) << " font \",12\"";
    gp << "\n";
  } else if (!figure.title.empty()) {
    gp << "set title " << Quote(figure.title) << " font ',12'\n";
  }
  for (std::size_t p = 0; p < figure.panels.size(); ++p) PanelScript(figure, p, abs_dir, files[p], gp);
  if (multi) gp << "unset multiplot\n";
  gp << "set output\n";
  return gp.str();
}

// Runs gnuplot on `script` with its output in `log`; false with *error
// (quoting the log's first lines) unless it exits 0.
bool RunGnuplot(const std::string& script, const std::string& log, std::string* error) {
  const char* env_gnuplot = std::getenv("PIDLAB_GNUPLOT");
  const std::string gnuplot = env_gnuplot && *env_gnuplot ? env_gnuplot : "gnuplot";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> argv = {const_cast<char*>(gnuplot.c_str()), const_cast<char*>(script.c_str()), nullptr};
  pid_t pid = 0;
  const int spawn_rc = posix_spawnp(&pid, gnuplot.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawn_rc != 0) {
    *error = "cannot run " + gnuplot + " (" + std::strerror(spawn_rc) +
             "); install Debian's gnuplot-nox or set PIDLAB_GNUPLOT";
    return false;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      *error = "waiting for gnuplot failed: " + std::string(std::strerror(errno));
      return false;
    }
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string why = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                        : "signal " + std::to_string(WTERMSIG(status));
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) why += " (gnuplot not found?)";
    *error = gnuplot + " failed with " + why + ": " + FirstLines(log, 3);
    return false;
  }
  return true;
}

}  // namespace

bool Figure::IsValid(std::string* error) const {
  std::ostringstream os;
  if (output_path.empty()) {
    os << "figure output_path is empty";
  } else if (width_px < 100 || width_px > 10000 || height_px < 100 || height_px > 10000) {
    os << "figure size " << width_px << "x" << height_px << " px must be within 100..10000 in each direction";
  } else if (panels.empty()) {
    os << "figure '" << title << "' has no panels";
  } else {
    for (std::size_t p = 0; p < panels.size() && os.tellp() == 0; ++p) {
      if (panels[p].series.empty()) os << "panel " << p << " ('" << panels[p].y_label << "') has no series";
      for (std::size_t s = 0; s < panels[p].series.size() && os.tellp() == 0; ++s) {
        const Series& se = panels[p].series[s];
        if (se.x.size() != se.y.size())
          os << "series '" << se.name << "' of panel " << p << " has " << se.x.size() << " x values but "
             << se.y.size() << " y values";
        else if (se.x.empty())
          os << "series '" << se.name << "' of panel " << p << " has no points";
      }
    }
  }
  if (os.tellp() == 0) return true;
  if (error) *error = os.str();
  return false;
}

namespace {

// DrawPng() with the refusal's message in *error.
bool DrawPngOrExplain(const Figure& figure, std::string* error) {
  if (!figure.IsValid(error)) return false;
  std::string e;
  auto fail = [&]() {
    if (error) *error = e;
    return false;
  };
  TempDir temp;
  std::string dir;
  if (!MakeDataDir(figure, &temp, &dir, &e)) return fail();
  std::vector<std::vector<std::string>> files;
  if (!WriteDataFiles(figure, dir, &files, &e)) return fail();

  // Paths are absolute so gnuplot's working folder does not matter.
  const std::string abs_dir = fs::absolute(dir).string();
  const std::string abs_out = fs::absolute(figure.output_path).string();
  // The script kept beside the data draws to the figure's own path; the one
  // run draws into a temporary folder, and the PNG is then written into
  // place whole (io::WriteFile): an old figure stays until a new one is
  // complete, and a full disk is named as such.
  if (const Status st = io::WriteFile(abs_dir + "/figure.gp", GnuplotScript(figure, abs_dir, abs_out, files));
      !st.ok()) {
    e = st.message();
    return fail();
  }
  TempDir run;
  if (!MakeTempDir(&run, &e)) return fail();
  const std::string drawn = run.path + "/figure.png", script = run.path + "/figure.gp";
  if (const Status st = io::WriteFile(script, GnuplotScript(figure, abs_dir, drawn, files)); !st.ok()) {
    e = st.message();
    return fail();
  }
  if (!RunGnuplot(script, run.path + "/gnuplot.log", &e)) return fail();
  int w = 0, h = 0;
  std::string png;
  if (!ReadPngSize(drawn, &w, &h) || !io::ReadFile(drawn, kMaxPngBytes, &png).ok()) {
    e = "gnuplot ran but wrote no PNG file for " + abs_out;
    return fail();
  }
  if (const Status st = io::WriteFile(abs_out, png); !st.ok()) {
    e = st.message();
    return fail();
  }
  return true;
}

}  // namespace

Status DrawPng(const Figure& figure) {
  std::string why;
  if (!DrawPngOrExplain(figure, &why)) return Status::IoFailed(why);
  return Status::Ok();
}

bool ReadPngSize(const std::string& path, int* width_px, int* height_px) {
  std::ifstream f(path, std::ios::binary);
  unsigned char b[24];
  if (!f.read(reinterpret_cast<char*>(b), sizeof b)) return false;
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (std::memcmp(b, kSignature, 8) != 0 || std::memcmp(b + 12, "IHDR", 4) != 0) return false;
  auto be32 = [](const unsigned char* p) {
    return static_cast<int>((static_cast<unsigned>(p[0]) << 24) | (p[1] << 16) | (p[2] << 8) | p[3]);
  };
  if (be32(b + 8) != 13) return false;
  *width_px = be32(b + 16);
  *height_px = be32(b + 20);
  return true;
}

}  // namespace pidlab::plot
