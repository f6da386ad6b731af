// Processor in the loop: the firmware's build and its QEMU (firmware.h).

#include "pidlab/pil/firmware.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace pidlab::pil {
namespace internal {
// The firmware's sources (controller/pil/firmware/, embedded by embed.cmake).
extern const char* const k_pil_startup_c;
extern const char* const k_pil_main_c;
extern const char* const k_pil_protocol_h;
extern const char* const k_pil_link_ld;
}  // namespace internal

namespace {

constexpr uint8_t kSync0 = 0xA5, kSync1 = 0x5A;
constexpr uint8_t kHello = 'H', kConfig = 'C', kStep = 'S', kStats = 'T';
constexpr uint8_t kInfo = 'I', kAck = 'A', kU = 'U', kStatsReply = 't', kError = 'E';

uint16_t Crc16(const uint8_t* p, std::size_t n, uint16_t crc) {
  for (std::size_t i = 0; i < n; ++i) {
    crc = static_cast<uint16_t>(crc ^ (p[i] << 8));
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint16_t>((crc & 0x8000U) ? (crc << 1) ^ 0x1021U : crc << 1);
  }
  return crc;
}

std::string Seconds(double s) {
  std::ostringstream os;
  os << s;
  return os.str();
}

double Now() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

bool OnPath(const std::string& name) {
  if (name.find('/') != std::string::npos) return access(name.c_str(), X_OK) == 0;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string d; std::getline(dirs, d, ':');)
    if (!d.empty() && access((d + "/" + name).c_str(), X_OK) == 0) return true;
  return false;
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

Status WriteText(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
  f.close();
  if (!f) return Status::IoFailed("cannot write '" + path + "'");
  return Status::Ok();
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string LastLine(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const std::size_t at = text.rfind('\n');
  return at == std::string::npos ? text : text.substr(at + 1);
}

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <typename T>
T Get(const std::string& in, std::size_t at) {
  T v{};
  std::memcpy(&v, in.data() + at, sizeof v);
  return v;
}

}  // namespace

bool ParseCore(const std::string& text, Core* core) {
  if (text == "m3") {
    *core = Core::kM3;
  } else if (text == "m4f") {
    *core = Core::kM4F;
  } else {
    return false;
  }
  return true;
}

std::string ToString(Core core) { return core == Core::kM3 ? "m3" : "m4f"; }

const char* QemuMachine(Core core) { return core == Core::kM3 ? "mps2-an385" : "mps2-an386"; }

std::string Toolchain::Missing() const {
  std::string missing;
  for (const std::string* tool : {&gcc, &size, &qemu})
    if (!OnPath(*tool)) missing += (missing.empty() ? "" : ", ") + *tool;
  if (missing.empty()) return "";
  return "the PIL toolchain is not installed (" + missing +
         " not found): run scripts/install-deps.sh --pil (gcc-arm-none-eabi, libnewlib-arm-none-eabi, "
         "qemu-system-arm)";
}

Status BuildFirmware(const controller_export::GeneratedCode& code, Core core, const std::string& dir,
                     const Toolchain& toolchain, FirmwareBuild* build) {
  if (const std::string missing = toolchain.Missing(); !missing.empty()) return Status::RunnerFailed(missing);
  if (mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST)
    return Status::IoFailed("cannot create '" + dir + "': " + std::strerror(errno));
  const std::vector<std::pair<std::string, std::string>> files = {
      {"pidlab_pid.h", code.header},
      {"pidlab_pid.c", code.source},
      {"pil_startup.c", internal::k_pil_startup_c},
      {"pil_main.c", internal::k_pil_main_c},
      {"pil_protocol.h", internal::k_pil_protocol_h},
      {"pil_link.ld", internal::k_pil_link_ld}};
  for (const auto& [name, text] : files)
    if (const Status st = WriteText(dir + "/" + name, text); !st.ok()) return st;
  const std::string cpu = core == Core::kM3 ? "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft"
                                            : "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16";
  char resolved[PATH_MAX];
  const std::string absolute = realpath(dir.c_str(), resolved) ? std::string(resolved) : dir;
  const std::string d = Quote(absolute);
  build->elf = absolute + "/pil.elf";
  build->command = toolchain.gcc + " " + cpu +
                   " -std=c99 -O2 -ffp-contract=off -ffunction-sections -fdata-sections -Wall -Wextra "
                   "-nostartfiles --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections -T " +
                   d + "/pil_link.ld -I" + d + " " + d + "/pil_startup.c " + d + "/pil_main.c " + d +
                   "/pidlab_pid.c -lm -o " + Quote(build->elf);
  // Extra flags for test builds (integration.pil's faults: -DPIL_FAULT=...).
  if (const char* extra = std::getenv("PIDLAB_PIL_CFLAGS"); extra && *extra)
    build->command += " " + std::string(extra);
  const std::string log = dir + "/build.log";
  if (std::system((build->command + " >" + Quote(log) + " 2>&1").c_str()) != 0)
    return Status::RunnerFailed("arm-none-eabi-gcc failed (" + log + "): " + LastLine(ReadText(log)));
  const std::string sizes = dir + "/size.txt";
  if (std::system((toolchain.size + " -A " + Quote(build->elf) + " >" + Quote(sizes) + " 2>&1").c_str()) != 0)
    return Status::RunnerFailed("arm-none-eabi-size failed: " + LastLine(ReadText(sizes)));
  std::istringstream lines(ReadText(sizes));
  for (std::string line; std::getline(lines, line);) {
    std::istringstream fields(line);
    std::string name;
    long bytes = 0;
    if (!(fields >> name >> bytes)) continue;
    if (name == ".text" || name == ".ARM.exidx") build->text += bytes;
    if (name == ".data") build->data += bytes;
    if (name == ".bss") build->bss += bytes;
    if (name == ".stack") build->stack_reserved += bytes;
  }
  if (build->text <= 0) return Status::RunnerFailed("no .text in '" + build->elf + "' (" + sizes + ")");
  return Status::Ok();
}

Status Firmware::Boot(const Options& options, std::unique_ptr<Firmware>* out) {
  if (!(options.deadline_s > 0.0) || !std::isfinite(options.deadline_s))
    return Status::InvalidInput("the PIL deadline " + Seconds(options.deadline_s) +
                                " s must be > 0 and finite");
  if (const std::string missing = options.toolchain.Missing(); !missing.empty())
    return Status::RunnerFailed(missing);
  if (access(options.elf.c_str(), R_OK) != 0)
    return Status::InvalidInput("firmware '" + options.elf + "': " + std::strerror(errno));
  std::unique_ptr<Firmware> fw(new Firmware());
  fw->options_ = options;
  fw->stderr_path_ = options.elf + ".qemu.log";
  int to_child[2], from_child[2];
  if (pipe(to_child) != 0 || pipe(from_child) != 0)
    return Status::RunnerFailed(std::string("pipe: ") + std::strerror(errno));
  const std::string machine = QemuMachine(options.core);
  std::vector<std::string> args = {options.toolchain.qemu,
                                   "-M",
                                   machine,
                                   "-nographic",
                                   "-monitor",
                                   "none",
                                   "-serial",
                                   "stdio",
                                   "-icount",
                                   "shift=0",
                                   "-kernel",
                                   options.elf};
  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child < 0) return Status::RunnerFailed(std::string("fork: ") + std::strerror(errno));
  if (child == 0) {
    // QEMU dies with its bridge: never an orphan.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    dup2(to_child[0], STDIN_FILENO);
    dup2(from_child[1], STDOUT_FILENO);
    const int err = open(fw->stderr_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (err >= 0) dup2(err, STDERR_FILENO);
    for (int fd : {to_child[0], to_child[1], from_child[0], from_child[1]}) close(fd);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  close(to_child[0]);
  close(from_child[1]);
  fw->qemu_ = child;
  fw->to_fw_ = to_child[1];
  fw->from_fw_ = from_child[0];
  fcntl(fw->from_fw_, F_SETFL, fcntl(fw->from_fw_, F_GETFL) | O_NONBLOCK);
  signal(SIGPIPE, SIG_IGN);
  std::string info;
  if (const Status st = fw->Send(kHello, ""); !st.ok()) return st;
  if (const Status st = fw->Receive(kInfo, &info); !st.ok()) return st;
  if (info.size() != 28)
    return Status::RunnerFailed("the firmware's PIL_INFO has " + std::to_string(info.size()) +
                                " bytes, not 28");
  const uint32_t scalar = Get<uint32_t>(info, 0);
  static const controller_export::Scalar kScalars[] = {
      controller_export::Scalar::kDouble, controller_export::Scalar::kFloat, controller_export::Scalar::kQ31,
      controller_export::Scalar::kQ15};
  if (scalar > 3) return Status::RunnerFailed("the firmware names scalar code " + std::to_string(scalar));
  fw->info_.scalar = kScalars[scalar];
  fw->info_.core = static_cast<int>(Get<uint32_t>(info, 4));
  fw->info_.q_bits = static_cast<int>(Get<uint32_t>(info, 8));
  fw->info_.input_full_scale = Get<double>(info, 12);
  fw->info_.output_full_scale = Get<double>(info, 20);
  *out = std::move(fw);
  return Status::Ok();
}

Firmware::~Firmware() {
  if (to_fw_ >= 0) close(to_fw_);
  if (from_fw_ >= 0) close(from_fw_);
  if (qemu_ <= 0) return;
  kill(qemu_, SIGTERM);
  for (int i = 0; i < 100; ++i) {  // 1 s for QEMU to go, then SIGKILL: reaped either way
    if (waitpid(qemu_, nullptr, WNOHANG) == qemu_) return;
    usleep(10000);
  }
  kill(qemu_, SIGKILL);
  waitpid(qemu_, nullptr, 0);
}

Status Firmware::Exited(const std::string& waiting_for) {
  int status = 0;
  std::string how = "closed its UART";
  if (qemu_ > 0) {
    for (int i = 0; i < 50; ++i) {
      const pid_t r = waitpid(qemu_, &status, WNOHANG);
      if (r == qemu_) {
        how = WIFEXITED(status) ? "exited with status " + std::to_string(WEXITSTATUS(status))
                                : "was killed by signal " + std::to_string(WTERMSIG(status));
        qemu_ = -1;
        break;
      }
      usleep(10000);
    }
  }
  const std::string last = LastLine(ReadText(stderr_path_));
  return Status::RunnerFailed("QEMU " + how + " while the bridge waited for " + waiting_for +
                              (last.empty() ? std::string() : ": " + last));
}

Status Firmware::SendRaw(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = write(to_fw_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Exited("its UART to take a frame");
    done += static_cast<std::size_t>(n);
  }
  return Status::Ok();
}

Status Firmware::Send(uint8_t type, const std::string& payload) {
  std::string frame = {static_cast<char>(kSync0), static_cast<char>(kSync1), static_cast<char>(type),
                       static_cast<char>(payload.size())};
  frame += payload;
  const uint16_t crc = Crc16(reinterpret_cast<const uint8_t*>(frame.data()) + 2, frame.size() - 2, 0xFFFF);
  frame += static_cast<char>(crc & 0xFF);
  frame += static_cast<char>(crc >> 8);
  return SendRaw(frame);
}

Status Firmware::ReadExact(uint8_t* p, std::size_t n, double deadline) {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = read(from_fw_, p + done, n - done);
    if (r > 0) {
      done += static_cast<std::size_t>(r);
      continue;
    }
    if (r == 0) return Exited("an answer");
    if (errno != EAGAIN && errno != EINTR) return Exited("an answer");
    const double left = deadline - Now();
    if (left <= 0.0)
      return Status::RunnerFailed("the firmware did not answer within the " + Seconds(options_.deadline_s) +
                                  " s deadline (stalled or faulted)");
    pollfd fd{from_fw_, POLLIN, 0};
    poll(&fd, 1, static_cast<int>(std::ceil(left * 1000.0)));
  }
  return Status::Ok();
}

Status Firmware::Receive(uint8_t want, std::string* payload) {
  const double deadline = Now() + options_.deadline_s;
  uint8_t head[4];
  if (const Status st = ReadExact(head, 4, deadline); !st.ok()) return st;
  if (head[0] != kSync0 || head[1] != kSync1) {
    char text[64];
    std::snprintf(text, sizeof text, "0x%02x 0x%02x", head[0], head[1]);
    return Status::RunnerFailed(std::string("a wrong frame from the firmware: ") + text +
                                " where a frame starts (0xa5 0x5a)");
  }
  std::vector<uint8_t> body(static_cast<std::size_t>(head[3]) + 2);
  if (const Status st = ReadExact(body.data(), body.size(), deadline); !st.ok()) return st;
  uint16_t crc = Crc16(head + 2, 2, 0xFFFF);
  crc = Crc16(body.data(), head[3], crc);
  const uint16_t got = static_cast<uint16_t>(body[head[3]] | (body[head[3] + 1] << 8));
  if (crc != got) return Status::RunnerFailed("a wrong frame from the firmware: its CRC does not match");
  if (head[2] == kError)
    return Status::RunnerFailed("the firmware refused the bridge's frame (error code " +
                                std::to_string(head[3] > 0 ? body[0] : 0) + ")");
  if (head[2] != want)
    return Status::RunnerFailed(std::string("a wrong frame from the firmware: type '") +
                                static_cast<char>(head[2]) + "' where '" + static_cast<char>(want) +
                                "' was due");
  payload->assign(reinterpret_cast<const char*>(body.data()), head[3]);
  return Status::Ok();
}

Status Firmware::Configure(const PidGains& gains, const PidOptions& pid, double b, double c,
                           int* init_status) {
  std::string p;
  for (double v : {gains.kp, gains.ki, gains.kd, pid.derivative_filter_s, b, c, pid.dt_s,
                   std::isfinite(pid.output_min) ? pid.output_min : 0.0,
                   std::isfinite(pid.output_max) ? pid.output_max : 0.0,
                   std::isfinite(pid.output_min) ? 1.0 : 0.0, std::isfinite(pid.output_max) ? 1.0 : 0.0,
                   static_cast<double>(static_cast<int>(pid.anti_windup)), pid.back_calculation_gain,
                   static_cast<double>(static_cast<int>(pid.integral)), pid.setpoint_filter_s})
    Put(&p, v);
  if (const Status st = Send(kConfig, p); !st.ok()) return st;
  std::string ack;
  if (const Status st = Receive(kAck, &ack); !st.ok()) return st;
  if (ack.size() != 4)
    return Status::RunnerFailed("the firmware's PIL_ACK has " + std::to_string(ack.size()) + " bytes");
  *init_status = Get<int32_t>(ack, 0);
  return Status::Ok();
}

Status Firmware::Step(double r, double y, StepReply* reply) {
  std::string p;
  const bool fixed = info_.q_bits != 0;
  if (fixed) {
    // pidlab-controller-c's rounding to the module's grid (controller_role_c.c).
    const double top = std::ldexp(1.0, info_.q_bits);
    for (double v : {r, y}) {
      const double q = std::floor(std::ldexp(v / info_.input_full_scale, info_.q_bits) + 0.5);
      Put(&p, static_cast<int64_t>(q < -top ? -top : (q > top - 1.0 ? top - 1.0 : q)));
    }
  } else {
    Put(&p, r);
    Put(&p, y);
  }
  if (const Status st = Send(kStep, p); !st.ok()) return st;
  std::string u;
  if (const Status st = Receive(kU, &u); !st.ok()) return st;
  if (u.size() != 13)
    return Status::RunnerFailed("the firmware's PIL_U has " + std::to_string(u.size()) + " bytes");
  reply->u =
      fixed ? static_cast<double>(Get<int64_t>(u, 0)) * std::ldexp(info_.output_full_scale, -info_.q_bits)
            : Get<double>(u, 0);
  reply->status = static_cast<uint8_t>(u[8]);
  reply->ticks = Get<uint32_t>(u, 9);
  return Status::Ok();
}

Status Firmware::Stats(uint32_t* stack_used, uint32_t* stack_size) {
  if (const Status st = Send(kStats, ""); !st.ok()) return st;
  std::string s;
  if (const Status st = Receive(kStatsReply, &s); !st.ok()) return st;
  if (s.size() != 8)
    return Status::RunnerFailed("the firmware's stats have " + std::to_string(s.size()) + " bytes");
  *stack_used = Get<uint32_t>(s, 0);
  *stack_size = Get<uint32_t>(s, 4);
  return Status::Ok();
}

}  // namespace pidlab::pil
