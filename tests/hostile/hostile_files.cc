// Hostile files against every file reader of pidlab, in process: a spec
// (--spec), a result (export --from), a model file (--plant model:FILE), a
// CSV record (identify --csv) and an LCM log (replay). From one valid seed
// of each, COUNT seeded cases a reader: truncation at every byte, bit flips,
// inserted NUL and non-UTF-8 bytes, deleted ranges, a UTF-8 BOM, CRLF line
// ends, NaN and overflowing number text, nesting to 10^6, strings to 10 MB,
// empty files, absurd scales (1e300, 1e13 times a column, t spacing of
// 1e-301). Each case is written to a file and read as the command reads it;
// every refusal must be one line of at most kMaxMessage characters. A crash
// (or, in the sanitised tree, a sanitizer report) ends the run.
//
// --samples DIR writes every --sample-every'th case to DIR as
// <reader>_<index>.<ext>, for the command-line pass of hostile_files_test.sh.
//
// usage: hostile_files [--count N] [--seed S] [--samples DIR --sample-every K]

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <pidlab/lcmt_episode_config.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "pidlab/identify/csv_data.h"
#include "pidlab/identify/identify.h"
#include "pidlab/io/files.h"
#include "pidlab/replay/log_reader.h"
#include "pidlab/spec/json.h"
#include "pidlab/spec/loop_spec.h"
#include "pidlab/transport/episode_spec.h"
#include "pidlab/tune/model_file.h"

// s.ok(), with its message in *error.
static bool OkWithMessage(const pidlab::Status& s, std::string* error) {
  if (error) *error = s.message();
  return s.ok();
}

namespace {

// A library's message; the command adds at most about 50 characters
// ("pidlab identify: error: --csv 'x': ").
constexpr std::size_t kMaxMessage = 250;
constexpr std::size_t kMaxJsonFileBytes = 1 << 20;

struct Reader {
  std::string name, ext;
  std::string seed;
  // Reads the file; false with *error when it refuses it.
  std::function<bool(const std::string& path, std::string* error)> read;
};

bool ReadJsonFile(const std::string& path, nlohmann::json* j, std::string* error) {
  std::string text;
  if (const pidlab::Status s = pidlab::io::ReadFile(path, kMaxJsonFileBytes, &text); !s.ok()) {
    *error = s.message();
    return false;
  }
  return OkWithMessage(pidlab::spec::ParseJsonText(text, j), error);
}

bool ReadSpec(const std::string& path, std::string* error) {
  nlohmann::json j;
  if (!ReadJsonFile(path, &j, error)) return false;
  if (j.is_object() && j.contains("spec") && j["spec"].is_object()) j = nlohmann::json(j["spec"]);
  pidlab::spec::EvaluateSpec evaluate;
  if (OkWithMessage(pidlab::spec::FromJson(j, &evaluate, nullptr), error)) return true;
  pidlab::spec::TuningSpec tuning;
  return OkWithMessage(pidlab::spec::FromJson(j, &tuning, nullptr), error);
}

bool ReadResult(const std::string& path, std::string* error) {
  nlohmann::json j;
  if (!ReadJsonFile(path, &j, error)) return false;
  if (!j.is_object() || !j.contains("spec") || !j["spec"].is_object() || !j.contains("gains") ||
      !j["gains"].is_object()) {
    *error = "not a result";
    return false;
  }
  pidlab::spec::EvaluateSpec evaluate;
  return OkWithMessage(pidlab::spec::FromJson(j["spec"], &evaluate, nullptr), error);
}

bool ReadModel(const std::string& path, std::string* error) {
  pidlab::Plant plant;
  const pidlab::Status st = pidlab::tune::ReadModelFile(path, &plant);
  if (error) *error = st.message();
  return st.ok();
}

bool ReadCsv(const std::string& path, std::string* error) {
  pidlab::identify::IdentifyData data;
  std::vector<long> rows;
  pidlab::Status s = pidlab::identify::ReadCsvData(path, &data, &rows);
  pidlab::identify::Sampling sampling;
  if (s.ok()) s = pidlab::identify::CheckData(data, &sampling, &rows);
  if (s.ok()) s = pidlab::identify::CheckResponse(data);
  *error = s.message();
  return s.ok();
}

bool ReadLogFile(const std::string& path, std::string* error) {
  pidlab::replay::LogContents contents;
  return OkWithMessage(pidlab::replay::ReadLog(path, pidlab::replay::ReadOptions{}, &contents), error);
}

// ---- Seeds

std::string SpecSeed() {
  pidlab::spec::EvaluateSpec s;
  s.plant.plant = "custom";
  s.plant.num = {1.0};
  s.plant.den = {10.0, 1.0};
  s.gains = {2.0, 0.2, 0.0};
  return pidlab::spec::ToJson(s).dump(1);
}

std::string ResultSeed() {
  nlohmann::json j;
  j["spec"] = nlohmann::json::parse(SpecSeed());
  j["gains"] = {{"kp", 2.0}, {"ki", 0.2}, {"kd", 0.0}};
  j["iae"] = 3.5;
  return j.dump(1);
}

std::string ModelSeed() {
  return R"({
 "model": "p1d",
 "parameters": {"Kp": {"value": 2.0, "se": 0.01}, "Tp1": {"value": 10.0, "se": 0.1},
                "Td": {"value": 1.5, "se": 0.02}},
 "covariance": {"ok": true, "matrix": [[1e-4, 0, 0], [0, 1e-2, 0], [0, 0, 4e-4]]},
 "transfer_function": {"num": [2.0], "den": [10.0, 1.0], "delay_s": 1.5}
})";
}

std::string CsvSeed() {
  std::string text = "t,u,y\n";
  char row[96];
  for (int k = 0; k < 60; ++k) {
    const double t = 0.5 * k, u = k >= 4 ? 1.0 : 0.0;
    const double y = t > 2.0 ? 2.0 * (1.0 - std::exp(-(t - 2.0) / 3.0)) : 0.0;
    std::snprintf(row, sizeof row, "%.3f,%.1f,%.6f\n", t, u, y);
    text += row;
  }
  return text;
}

void PutBigEndian(std::string* out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

// lcm-logger's format: per event the sync word, the event number, the time
// (us), the channel's and the data's lengths, the channel and the data.
void PutEvent(std::string* log, std::uint64_t number, std::uint64_t utime, const std::string& channel,
              const std::string& data) {
  PutBigEndian(log, 0xEDA1DA01u, 4);
  PutBigEndian(log, number, 8);
  PutBigEndian(log, utime, 8);
  PutBigEndian(log, channel.size(), 4);
  PutBigEndian(log, data.size(), 4);
  *log += channel;
  *log += data;
}

std::string LogSeed() {
  pidlab::transport::EpisodeSpec spec;
  spec.episode_id = 42;
  spec.plant.tf.num = {1.0};
  spec.plant.tf.den = {1.0, 1.0};
  spec.gains = {1.0, 0.5, 0.0};
  spec.dt_s = 0.01;
  spec.pid.dt_s = 0.01;
  spec.sample_time_s = 0.05;
  spec.horizon_s = 1.0;
  spec.total_steps = 100;
  pidlab::lcmt_episode_config message = pidlab::transport::MakeEpisodeConfig(spec);
  std::string bytes(static_cast<std::size_t>(message.getEncodedSize()), '\0');
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  std::string log;
  PutEvent(&log, 0, 1000, "PIDLAB_EPISODE_CONFIG", bytes);
  PutEvent(&log, 1, 2000, "PIDLAB_OTHER", "hello");
  PutEvent(&log, 2, 3000, "PIDLAB_EPISODE_CONFIG", bytes);
  return log;
}

// ---- Mutations

class Mutator {
 public:
  Mutator(std::uint64_t seed, long index, const std::string& ext) : ext_(ext) {
    std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                      static_cast<std::uint32_t>(index)};
    rng_.seed(seq);
    index_ = index;
  }

  std::string Mutate(const std::string& seed) {
    std::string s = seed;
    const bool json = ext_ == "json", csv = ext_ == "csv";
    switch (index_ % 16) {
      case 0:  // truncation, moving over the file with the cases
        return s.substr(0, static_cast<std::size_t>(index_ / 16) % (s.size() + 1));
      case 1:
        for (int i = Uniform(1, 8); i > 0; --i) s[Position(s)] ^= static_cast<char>(1 << Uniform(0, 7));
        return s;
      case 2:
        for (int i = Uniform(1, 6); i > 0; --i) s.insert(Position(s), 1, static_cast<char>(Uniform(0, 255)));
        return s;
      case 3: {
        const std::size_t at = Position(s);
        return s.erase(at, static_cast<std::size_t>(Uniform(1, 64)));
      }
      case 4:
        return "\xef\xbb\xbf" + s;
      case 5: {
        std::string out;
        for (char c : s) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
        return out;
      }
      case 6:
        return ReplaceNumber(s, Pick({"NaN", "nan", "inf", "-inf", "1e309", "-1e400", "1e300", "0x1p3", "",
                                      "1e-320", "\"1\"", "null", "true", "[]", "{}"}));
      case 7:
        if (json) return Nest(s, Pick({65, 1000, 100000, 1000000}));
        if (csv) return Scale(s, Pick({1e13, 1e300, 1e-301}));
        break;
      case 8:
        if (json) return ReplaceNumber(s, "\"" + std::string(Pick({1000, 1 << 20, 10 << 20}), 'x') + "\"");
        if (csv) return AddRow(s, "1e300,1,1");
        return s + std::string(static_cast<std::size_t>(Pick({1000, 1 << 20})), '\0');
      case 9:
        return "";
      case 10:
        if (csv) return TimeScale(s, 1e-301);
        if (json) return ReplaceNumber(s, "\"\xff\xfe\xc0\xaf\"");
        break;
      case 11:
        if (csv) return ConstantY(s);
        if (json) return "[" + s + "]";
        break;
      case 12:
        if (json) return s.substr(0, s.size() / 2) + std::string(Pick({100, 100000}), '{');
        if (csv) return "\"t\",\"u\",\"y\"" + s.substr(s.find('\n'));
        break;
      case 13: {  // a splice of two places of the same file
        const std::size_t a = Position(s), b = Position(s);
        return s.substr(0, std::min(a, b)) + s.substr(std::max(a, b));
      }
      default:
        break;
    }
    // Several of the above at once.
    for (int i = Uniform(2, 4); i > 0; --i) {
      const std::size_t at = Position(s);
      s[at] = static_cast<char>(Uniform(0, 255));
    }
    return s;
  }

 private:
  int Uniform(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  std::size_t Position(const std::string& s) {
    return s.empty() ? 0 : std::uniform_int_distribution<std::size_t>(0, s.size() - 1)(rng_);
  }
  template <typename T>
  T Pick(std::initializer_list<T> values) {
    return *(values.begin() + Uniform(0, static_cast<int>(values.size()) - 1));
  }
  std::string Pick(std::initializer_list<const char*> values) {
    return *(values.begin() + Uniform(0, static_cast<int>(values.size()) - 1));
  }

  // A number of the text (a run of digits) replaced by `with`.
  std::string ReplaceNumber(const std::string& s, const std::string& with) {
    std::vector<std::size_t> starts;
    for (std::size_t i = 0; i < s.size(); ++i)
      if (std::isdigit(static_cast<unsigned char>(s[i])) &&
          (i == 0 || !std::isdigit(static_cast<unsigned char>(s[i - 1]))))
        starts.push_back(i);
    if (starts.empty()) return s + with;
    const std::size_t at = starts[static_cast<std::size_t>(Uniform(0, static_cast<int>(starts.size()) - 1))];
    std::size_t end = at;
    while (end < s.size() && (std::isdigit(static_cast<unsigned char>(s[end])) || s[end] == '.')) ++end;
    return s.substr(0, at) + with + s.substr(end);
  }
  std::string Nest(const std::string& s, int depth) {
    return ReplaceNumber(s, std::string(static_cast<std::size_t>(depth), '[') + "1" +
                                std::string(static_cast<std::size_t>(depth), ']'));
  }
  // Every row's column c (0 t, 1 u, 2 y) times `factor`.
  std::string MapColumn(const std::string& s, int c, const std::function<double(double, long)>& f) {
    std::istringstream in(s);
    std::string line, out;
    std::getline(in, line);
    out = line + "\n";
    for (long row = 0; std::getline(in, line); ++row) {
      std::vector<std::string> cells;
      std::stringstream ss(line);
      for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
      if (static_cast<int>(cells.size()) > c) {
        char v[40];
        std::snprintf(v, sizeof v, "%.17g", f(std::atof(cells[static_cast<std::size_t>(c)].c_str()), row));
        cells[static_cast<std::size_t>(c)] = v;
      }
      for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? "," : "") + cells[i];
      out += "\n";
    }
    return out;
  }
  std::string Scale(const std::string& s, double factor) {
    return MapColumn(s, Uniform(0, 2), [factor](double v, long) { return v * factor; });
  }
  std::string TimeScale(const std::string& s, double dt) {
    return MapColumn(s, 0, [dt](double, long row) { return static_cast<double>(row) * dt; });
  }
  std::string ConstantY(const std::string& s) {
    return MapColumn(s, 2, [](double, long) { return 0.25; });
  }
  std::string AddRow(const std::string& s, const std::string& row) {
    const std::size_t first = s.find('\n');
    return first == std::string::npos ? s + "\n" + row
                                      : s.substr(0, first + 1) + row + "\n" + s.substr(first + 1);
  }

  std::mt19937_64 rng_;
  long index_ = 0;
  std::string ext_;
};

bool WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(f.flush());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hostile files against pidlab's file readers, in process"};
  long count = 10000;
  std::uint64_t seed = 1;
  std::string samples;
  long sample_every = 100;
  app.add_option("--count", count, "cases per reader")->capture_default_str();
  app.add_option("--seed", seed, "the generator's seed")->capture_default_str();
  app.add_option("--samples", samples, "also write every --sample-every'th case into this folder");
  app.add_option("--sample-every", sample_every)->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const std::vector<Reader> readers = {
      {"spec", "json", SpecSeed(), ReadSpec},    {"result", "json", ResultSeed(), ReadResult},
      {"model", "json", ModelSeed(), ReadModel}, {"csv", "csv", CsvSeed(), ReadCsv},
      {"log", "lcmlog", LogSeed(), ReadLogFile},
  };
  // In memory where the machine has it: 5 x 10^4 files, some of 10 MB.
  std::string dir_pattern = std::string(std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp") +
                            "/pidlab-hostile-files-XXXXXX";
  if (!mkdtemp(dir_pattern.data())) {
    std::cerr << "cannot create a temporary folder\n";
    return 1;
  }
  const std::string dir = dir_pattern;
  int failures = 0;
  for (const Reader& r : readers) {
    std::string error;
    const std::string seed_path = dir + "/seed." + r.ext;
    WriteBytes(seed_path, r.seed);
    if (!r.read(seed_path, &error)) {
      std::cout << "FAIL " << r.name << ": the valid seed is refused: " << error << "\n";
      ++failures;
      continue;
    }
    long refused = 0, accepted = 0;
    // The seed cut at every byte, then `count` seeded mutants.
    const long cuts = static_cast<long>(r.seed.size());
    for (long i = 0; i < cuts + count; ++i) {
      const std::string bytes = i < cuts ? r.seed.substr(0, static_cast<std::size_t>(i))
                                         : Mutator(seed, i - cuts, r.ext).Mutate(r.seed);
      const std::string path = dir + "/case." + r.ext;
      if (!WriteBytes(path, bytes)) {
        std::cout << "FAIL cannot write " << path << "\n";
        return 1;
      }
      if (!samples.empty() && i % sample_every == 0)
        WriteBytes(samples + "/" + r.name + "_" + std::to_string(i) + "." + r.ext, bytes);
      error.clear();
      if (r.read(path, &error)) {
        ++accepted;
        continue;
      }
      ++refused;
      if (error.empty() || error.size() > kMaxMessage || error.find('\n') != std::string::npos) {
        if (++failures <= 10)
          std::cout << "FAIL " << r.name << " case " << i << ": the refusal is not one line of at most "
                    << kMaxMessage << " characters (" << error.size() << "): " << error.substr(0, 300)
                    << "\n";
      }
    }
    std::cout << r.name << ": " << cuts + count << " cases (" << cuts << " cuts, one at every byte, and "
              << count << " mutants), " << refused << " refused, " << accepted << " read, no crash\n";
  }
  std::filesystem::remove_all(dir);
  std::cout << failures << " failures\n";
  return failures == 0 ? 0 : 1;
}
