// The device's control loop around fivebar::runtime (docs/runtime.md "Device loop"): the starting
// point of the device's ROS 2 node. It reads the exported configuration, then every period reads the
// joints and the reference points from an I/O backend, runs one cycle, and writes the duties.
//
//   device_loop CONFIG.json [IN.csv|-] [--realtime] [--rt-priority N] [--watchdog N] [--channels MAP.csv]
//               [--io csv|linux] [--sysfs-root DIR] [--iio-device N] [--pwm-chip N] [--estop-gpio N]
//
// The backend here is a CSV stream standing in for the DAQ and the motor drivers: each input row
// holds time_s, per joint <joint>_counts (or _volts, _theta_rad), per mechanism
// <station>_<mechanism>_x_ref_mm and _y_ref_mm (the log format of `fivebar replay`; other columns,
// such as logged duties, are ignored); each output row (stdout) holds time_s, the duties
// <joint>_duty and the statuses <station>_<mechanism>_status. A ROS node replaces CsvIo by an
// implementation of DeviceIo over its DAQ driver, its PWM outputs and its reference topic, and the
// loop by a wall timer at loop_rate_hz. Nothing in the loop allocates after the controller is built.
//
// Watchdog on stale references: a row whose reference cells are all empty (or cut off) brings no new reference
// points (the last ones stay, as a ROS node keeps the last message); after more than N such cycles in
// a row (--watchdog, default 10: 0.1 s at the showcase's 100 Hz, an assumption, not a measured
// figure) every duty is 0, the statuses read `stale` and the controller is reset, until a row brings
// references again.
//
// Whenever the loop ends (the end of the input, SIGINT or SIGTERM, an input error) the last thing it
// writes is zero duty to every motor (DeviceIo::stop(); CsvIo: a row of zero duties whose statuses
// read `stopped`); exit 0 at the end of the input, 128 + the signal's number, 2 on an error.
//
// E-stop: the input `estop` (CsvIo: an optional column `estop`, 0 or 1) or SIGUSR1 latches it: from
// that cycle on every duty is 0, the statuses read `estop` and the controller is reset, whatever the
// input does, until an explicit reset (CsvIo: a row whose optional `estop_reset` cell is 1, or
// SIGUSR2) while the E-stop input is not active; then the loop runs again from a reset controller
// (the slew limit starts from where the joints are).
//
// --channels MAP.csv: where each joint is wired (its ADC and PWM channels, the motor's direction, an
// offset in ADC codes; read_channel_map()): the readings are then the columns adc<k>_counts and the
// duties go out as pwm<k>_duty, each joint's duty times its direction.
//
// --realtime: the loop paces itself at loop_rate_hz with absolute deadlines (clock_nanosleep
// TIMER_ABSTIME on CLOCK_MONOTONIC), runs under SCHED_FIFO (priority --rt-priority, default 80, an
// assumption: above ordinary threads and the kernel's threaded interrupts at 50) and locks its memory
// (mlockall MCL_CURRENT | MCL_FUTURE) where permitted, saying on stderr when not and going on. A
// cycle whose output comes after its deadline (the next period's start) is an overrun: the row's
// `overrun` column is 1, the next cycle starts at once and the deadlines start again from it (no
// burst of cycles to catch up); the count is printed on stderr at the end.
//
// --io linux (LinuxIo; docs/runtime.md "Linux I/O"): the joints are read from the kernel's IIO files
// and the duties go to its PWM and GPIO files (fivebar/runtime/linux_io.hpp), wired by the channel
// map (which then needs the column direction_gpio); the input stream brings only time_s, the
// reference points and the E-stop columns, and the output is the log in the replay format
// (`fivebar replay` reads it: readings, a failed one as an empty cell, duties, references,
// statuses). A write that fails is an error: zero duty is attempted on every channel, exit 2.

#include <signal.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <charconv>
#include <csignal>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "fivebar/runtime.hpp"
#include "fivebar/runtime/linux_io.hpp"

namespace rt = fivebar::runtime;
namespace lio = fivebar::runtime::linux_io;

/// One sample of the device's inputs besides the joints and the references.
struct Inputs {
  double t_s = 0.0;
  bool fresh = false;        ///< reference points came this cycle (else `targets_m` is left as it was)
  bool estop = false;        ///< the E-stop input is active
  bool estop_reset = false;  ///< an explicit request to release a latched E-stop
};

/// What the loop needs from the hardware (or its stand-in).
class DeviceIo {
 public:
  virtual ~DeviceIo() = default;
  /// The next sample: readings (joint order), reference points (m, 2 per mechanism) and the other
  /// inputs; false at the end.
  virtual bool read(Inputs& in, double* readings, double* targets_m) = 0;
  /// The duties (joint order) and statuses (mechanism order) of this cycle; `overrun`: it came after
  /// its deadline (--realtime).
  virtual void write(double t_s, const double* duties, const rt::Status* statuses, bool overrun) = 0;
  /// Zero duty to every motor, every status `status` (`stale`, `estop`).
  virtual void write_zero(double t_s, const char* status, bool overrun) = 0;
  /// An event for the log (`estop: latched (SIGUSR1)`).
  virtual void note(const char* what) = 0;
  virtual rt::Reading kind() const = 0;
  /// Zero duty to every motor: the loop's last output, whatever ends it (`why`: what did); false
  /// if that could not be written.
  virtual bool stop(double t_s, const char* why) = 0;
};

/// Where each joint is wired (--channels FILE): its ADC channel, its PWM channel, the motor's
/// direction (-1: wired reversed, the duty's sign flipped at the output) and an offset in ADC codes
/// added to the channel's code before it is the joint's reading. The file is CSV with the header
/// `joint,adc_channel,pwm_channel,direction,offset_counts`, one row per joint of the configuration's
/// stations (the ones the input has); channels whole numbers >= 0, each used once per kind.
struct Channel {
  long adc = -1, pwm = -1, gpio = -1;  ///< gpio: the direction line (optional column direction_gpio)
  double direction = 1.0, offset_counts = 0.0;
};
struct ChannelMap {
  std::string path;                       ///< the file, for messages
  std::map<std::string, Channel> joints;  ///< by joint name
  bool has_gpio = false;                  ///< the file has the column direction_gpio (needed by --io linux)
};

ChannelMap read_channel_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read");
  std::string line;
  const std::string header = "joint,adc_channel,pwm_channel,direction,offset_counts";
  ChannelMap map;
  map.path = path;
  std::map<long, std::string> adc_used, pwm_used, gpio_used;
  for (int n = 1; std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string at = path + ":" + std::to_string(n) + ": ";
    if (n == 1) {
      map.has_gpio = line == header + ",direction_gpio";
      if (line != header && !map.has_gpio) throw std::runtime_error(at + "expected the header " + header + " (and optionally ,direction_gpio)");
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    const std::size_t expected = map.has_gpio ? 6 : 5;
    if (cells.size() != expected) throw std::runtime_error(at + "expected " + std::to_string(expected) + " cells");
    const auto number = [&](std::size_t i, const char* key) {
      double x = 0.0;
      const std::string& t = cells[i];
      const auto r = std::from_chars(t.data(), t.data() + t.size(), x);
      if (t.empty() || r.ec != std::errc() || r.ptr != t.data() + t.size()) throw std::runtime_error(at + key + ": '" + t + "' is not a number");
      return x;
    };
    const auto channel = [&](std::size_t i, const char* key, std::map<long, std::string>& used) {
      const double x = number(i, key);
      if (!(x >= 0.0 && x <= 1e6 && x == std::floor(x))) throw std::runtime_error(at + key + ": expected a whole number >= 0");
      const long c = static_cast<long>(x);
      if (used.count(c)) throw std::runtime_error(at + key + ": channel " + std::to_string(c) + " is also " + used[c] + "'s");
      used[c] = cells[0];
      return c;
    };
    Channel ch;
    if (map.joints.count(cells[0])) throw std::runtime_error(at + "joint: " + cells[0] + " is mapped twice");
    ch.adc = channel(1, "adc_channel", adc_used);
    ch.pwm = channel(2, "pwm_channel", pwm_used);
    ch.direction = number(3, "direction");
    if (ch.direction != 1.0 && ch.direction != -1.0) throw std::runtime_error(at + "direction: expected 1 or -1");
    ch.offset_counts = number(4, "offset_counts");
    if (!(std::fabs(ch.offset_counts) <= 1e9)) throw std::runtime_error(at + "offset_counts: expected a finite number of codes");
    if (map.has_gpio) ch.gpio = channel(5, "direction_gpio", gpio_used);
    map.joints[cells[0]] = ch;
  }
  return map;
}

/// CSV on streams: a recorded or piped log in, duties out.
class CsvIo : public DeviceIo {
 public:
  /// Reads the header; a station of `c` with no column in it is left out of `c` (a log of one
  /// station runs against the export of several, as `fivebar replay` reads it).
  /// With a channel map the readings are ADC codes in columns `adc<k>_counts` and the duties go to
  /// columns `pwm<k>_duty` (joint order), each through its joint's channels, direction and offset.
  /// With `linux_base` (--io linux; needs `channels`): the readings come from the kernel's IIO files
  /// and the duties go to its PWM and GPIO files (LinuxIo, wired by the channel map), the input
  /// brings only time_s, the references and the E-stop columns, and the output is the replay log.
  CsvIo(std::istream& in, std::ostream& out, rt::Config& c, bool log_overruns, const ChannelMap* channels,
        const lio::LinuxIoConfig* linux_base = nullptr)
      : in_(in), out_(out), log_overruns_(log_overruns) {
    std::string line;
    if (!next_line(line)) throw std::runtime_error("input: no header row");
    const std::vector<std::string> header = split(line);
    header_ = header;
    std::map<std::string, std::size_t> at;
    for (std::size_t i = 0; i < header.size(); ++i) at[header[i]] = i;
    const auto column = [&](const std::string& name) {
      const auto it = at.find(name);
      if (it == at.end()) throw std::runtime_error("input: column " + name + " is missing");
      return it->second;
    };
    const auto has_columns = [&](const rt::StationConfig& st) {
      for (const auto& [name, index] : at)
        if (name.rfind(st.name + "_", 0) == 0) return true;
      return false;
    };
    c.stations.erase(std::remove_if(c.stations.begin(), c.stations.end(), [&](const rt::StationConfig& st) { return !has_columns(st); }),
                     c.stations.end());
    if (c.stations.empty()) throw std::runtime_error("input: no station of the configuration has columns");
    const std::string first = c.stations.front().mechanisms.front().joints[0].name;
    kind_ = channels || linux_base || at.count(first + "_counts") ? rt::Reading::counts
            : at.count(first + "_volts")          ? rt::Reading::volts
                                                  : rt::Reading::radians;
    const char* suffix = kind_ == rt::Reading::counts ? "_counts" : kind_ == rt::Reading::volts ? "_volts" : "_theta_rad";
    time_ = column("time_s");
    const auto optional = [&](const char* name) { return at.count(name) ? static_cast<long>(at[name]) : -1L; };
    estop_ = optional("estop");
    estop_reset_ = optional("estop_reset");
    out_ << "time_s";
    lio::LinuxIoConfig wiring;
    std::string ref_header;
    if (linux_base) wiring = *linux_base;
    for (const auto& s : c.stations)
      for (const auto& m : s.mechanisms) {
        for (const auto& j : m.joints) {
          if (linux_base) {
            const auto ch = channels->joints.find(j.name);
            if (ch == channels->joints.end()) throw std::runtime_error(channels->path + ": joint " + j.name + " has no row");
            wiring.joints.push_back({static_cast<int>(ch->second.adc), static_cast<int>(ch->second.pwm),
                                     static_cast<int>(ch->second.gpio), ch->second.direction, ch->second.offset_counts});
            joint_names_.push_back(j.name);
            out_ << "," << j.name << "_counts," << j.name << "_duty";  // the replay log (fivebar/replay.hpp)
            direction_.push_back(1.0);  // the direction is applied by LinuxIo, the log holds the joint's duty
            offset_.push_back(0.0);
          } else if (channels) {
            const auto ch = channels->joints.find(j.name);
            if (ch == channels->joints.end()) throw std::runtime_error(channels->path + ": joint " + j.name + " has no row");
            reading_.push_back(column("adc" + std::to_string(ch->second.adc) + "_counts"));
            out_ << ",pwm" << ch->second.pwm << "_duty";
            direction_.push_back(ch->second.direction);
            offset_.push_back(ch->second.offset_counts);
          } else {
            reading_.push_back(column(j.name + suffix));
            out_ << "," << j.name << "_duty";
            direction_.push_back(1.0);
            offset_.push_back(0.0);
          }
        }
        target_.push_back(column(s.name + "_" + m.name + "_x_ref_mm"));
        target_.push_back(column(s.name + "_" + m.name + "_y_ref_mm"));
        if (linux_base) ref_header += "," + s.name + "_" + m.name + "_x_ref_mm," + s.name + "_" + m.name + "_y_ref_mm";
      }
    if (linux_base) {
      out_ << ref_header;  // after every joint's columns, as log_row() writes them
      pins_ = std::make_unique<lio::LinuxIo>(wiring);  // sets every channel up, or IoError naming the file
      last_readings_.assign(joint_names_.size(), 0.0);
      last_targets_mm_.assign(target_.size(), 0.0);
    }
    for (const auto& s : c.stations)
      for (const auto& m : s.mechanisms) out_ << "," << s.name << "_" << m.name << "_status";
    if (log_overruns_) out_ << ",overrun";
    out_ << "\n";
    out_.precision(17);
  }
  bool read(Inputs& in, double* readings, double* targets) override {
    std::string line;
    if (!next_line(line)) return false;
    const std::vector<std::string> cells = split(line);
    // The whole cell is the number (std::from_chars: no locale, no `41496junk` read as 41496, no
    // hex); a short row or a cell that is not one is an error naming its line and column.
    const auto cell = [&](std::size_t i) {
      if (i >= cells.size()) throw std::runtime_error("input:" + std::to_string(line_) + ": column " + header_[i] + " is missing");
      const std::string& text = cells[i];
      double x = 0.0;
      const auto r = std::from_chars(text.data(), text.data() + text.size(), x);
      if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size()) {
        throw std::runtime_error("input:" + std::to_string(line_) + ": " + header_[i] + ": '" + text.substr(0, 32) +
                                 "' is not a number");
      }
      return x;
    };
    // The E-stop cells, when the columns are there: 0 or 1.
    const auto flag = [&](long i) {
      if (i < 0) return false;
      const double x = cell(static_cast<std::size_t>(i));
      if (x != 0.0 && x != 1.0) {
        throw std::runtime_error("input:" + std::to_string(line_) + ": " + header_[static_cast<std::size_t>(i)] + ": expected 0 or 1");
      }
      return x == 1.0;
    };
    in.t_s = cell(time_);
    if (pins_) {
      pins_->read(readings);  // a failed reading is NaN: the runtime's sensor fault, an empty cell in the log
      std::copy(readings, readings + last_readings_.size(), last_readings_.begin());
    }
    for (std::size_t i = 0; i < reading_.size(); ++i) readings[i] = cell(reading_[i]) + offset_[i];
    in.estop = flag(estop_);
    if (pins_ && pins_->estop()) in.estop = true;  // the E-stop line (--estop-gpio), or the input's column
    in.estop_reset = flag(estop_reset_);
    // Every reference cell empty: no new reference this cycle (else each must be a number).
    in.fresh = false;
    for (std::size_t i : target_) in.fresh = in.fresh || (i < cells.size() && !cells[i].empty());
    if (in.fresh)
      for (std::size_t i = 0; i < target_.size(); ++i) {
        const double mm = cell(target_[i]);
        targets[i] = mm / 1000.0;
        if (pins_) last_targets_mm_[i] = mm;  // logged as read: the replay divides it as this loop did
      }
    return true;
  }
  void write(double t, const double* duties, const rt::Status* statuses, bool overrun) override {
    if (pins_) {
      if (!pins_->write(duties)) throw std::runtime_error(std::string("write failed: ") + pins_->error());
      log_row(t, duties);
      for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << "," << rt::to_string(statuses[k]);
      end_row(overrun);
      return;
    }
    out_ << t;
    for (std::size_t i = 0; i < reading_.size(); ++i) out_ << "," << direction_[i] * duties[i];
    for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << "," << rt::to_string(statuses[k]);
    end_row(overrun);
  }
  void write_zero(double t, const char* status, bool overrun) override {
    if (pins_) {
      if (!pins_->write_zero()) throw std::runtime_error(std::string("write failed: ") + pins_->error());
      // Not a cycle of the runtime: a note, so the log stays what `fivebar replay` runs.
      out_ << "# " << status << ": t = " << t << " s, zero duty" << (overrun ? ", overrun" : "") << "\n";
      out_.flush();
      return;
    }
    out_ << t;
    for (std::size_t i = 0; i < reading_.size(); ++i) out_ << ",0";
    for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << "," << status;
    end_row(overrun);
  }
  void note(const char* what) override { out_ << "# " << what << "\n"; }
  rt::Reading kind() const override { return kind_; }
  bool stop(double t, const char* why) override {
    out_ << "# stopped: " << why << "\n";
    if (pins_ && !pins_->write_zero()) {  // every channel attempted
      out_ << "# zero duty not written: " << pins_->error() << "\n";
      out_.flush();
      std::cerr << "device_loop: zero duty not written: " << pins_->error() << "\n";
      return false;
    }
    if (pins_) {  // a note only: the log stays the runtime's cycles
      out_ << "# zero duty written to every channel\n";
      out_.flush();
      return true;
    }
    write_zero(t, "stopped", false);
    return true;
  }

 private:
  /// --io linux: time, per joint the reading (empty where it failed) and the duty, the references
  /// (mm): the replay log's columns before the statuses.
  void log_row(double t, const double* duties) {
    out_ << t;
    for (std::size_t i = 0; i < last_readings_.size(); ++i) {
      out_ << ",";
      if (!std::isnan(last_readings_[i])) out_ << last_readings_[i];
      out_ << "," << duties[i];
    }
    for (double v : last_targets_mm_) out_ << "," << v;
  }
  void end_row(bool overrun) {
    if (log_overruns_) out_ << (overrun ? ",1" : ",0");
    out_ << "\n";
    out_.flush();  // a pipe's reader (the motor driver's stand-in) sees every cycle at once
  }
  /// The next line that is neither blank nor a `#` comment (the logs' notes, as `fivebar replay` reads them).
  bool next_line(std::string& line) {
    while (std::getline(in_, line)) {
      ++line_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::size_t first = line.find_first_not_of(" \t");
      if (first != std::string::npos && line[first] != '#') return true;
    }
    return false;
  }
  static std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell);
    return out;
  }
  std::istream& in_;
  std::ostream& out_;
  bool log_overruns_ = false;
  long estop_ = -1, estop_reset_ = -1;  ///< optional columns (-1: absent)
  rt::Reading kind_ = rt::Reading::counts;
  std::size_t time_ = 0;
  std::size_t line_ = 0;  ///< 1-based line of the last line read
  std::vector<std::string> header_;
  std::vector<std::size_t> reading_, target_;
  std::vector<double> direction_, offset_;  ///< per joint: the channel map's (1 and 0 without one)
  std::unique_ptr<lio::LinuxIo> pins_;      ///< --io linux
  std::vector<std::string> joint_names_;
  std::vector<double> last_readings_, last_targets_mm_;  ///< --io linux: this cycle's, for the log
};

namespace {
volatile std::sig_atomic_t g_signal = 0;
// SIGUSR1 latches the E-stop, SIGUSR2 asks to release it: counters only the handler writes.
volatile std::sig_atomic_t g_estop_signals = 0, g_reset_signals = 0;
extern "C" void on_signal(int signal_number) { g_signal = signal_number; }
extern "C" void on_estop(int signal_number) {
  if (signal_number == SIGUSR1) g_estop_signals = g_estop_signals + 1;
  else g_reset_signals = g_reset_signals + 1;
}

struct Options {
  std::string config, input = "-", channels;
  bool realtime = false;
  long watchdog = 10;
  long priority = 80;
  std::string io = "csv";        ///< --io csv|linux
  std::string sysfs_root = "/";  ///< --sysfs-root: where sys/ is (a scratch folder in tests)
  long iio_device = 0, pwm_chip = 0;
  long estop_gpio = -1;  ///< --estop-gpio N (--io linux): the E-stop input line
};

/// A whole number in [lo, hi] after `flag`, or exit 2 naming both.
bool whole(const std::string& flag, const std::string& value, long lo, long hi, long& out) {
  const auto r = std::from_chars(value.data(), value.data() + value.size(), out);
  if (value.empty() || r.ec != std::errc() || r.ptr != value.data() + value.size() || out < lo || out > hi) {
    std::cerr << "device_loop: " << flag << " " << value << ": expected a whole number in [" << lo << ", " << hi << "]\n";
    return false;
  }
  return true;
}

bool parse(int argc, char** argv, Options& o) {
  if (argc < 2) {
    std::cerr << "usage: device_loop CONFIG.json [IN.csv|-] [--realtime] [--rt-priority N] [--watchdog N] [--channels MAP.csv]\n"
                 "                   [--io csv|linux] [--sysfs-root DIR] [--iio-device N] [--pwm-chip N] [--estop-gpio N]\n";
    return false;
  }
  o.config = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--realtime") {
      o.realtime = true;
    } else if (arg == "--channels") {
      o.channels = i + 1 < argc ? argv[++i] : "";
      if (o.channels.empty()) {
        std::cerr << "device_loop: --channels: expected a file name\n";
        return false;
      }
    } else if (arg == "--io" || arg == "--sysfs-root") {
      const std::string value = i + 1 < argc ? argv[++i] : "";
      if (arg == "--io" && value != "csv" && value != "linux") {
        std::cerr << "device_loop: --io " << value << ": expected csv or linux\n";
        return false;
      }
      if (value.empty()) {
        std::cerr << "device_loop: " << arg << ": expected a value\n";
        return false;
      }
      (arg == "--io" ? o.io : o.sysfs_root) = value;
    } else if (arg == "--iio-device" || arg == "--pwm-chip" || arg == "--estop-gpio") {
      const std::string value = i + 1 < argc ? argv[++i] : "";
      if (!whole(arg, value, 0, 1000000, arg == "--iio-device" ? o.iio_device : arg == "--pwm-chip" ? o.pwm_chip : o.estop_gpio)) return false;
    } else if (arg == "--watchdog" || arg == "--rt-priority") {
      const std::string value = i + 1 < argc ? argv[++i] : "";
      if (!(arg == "--watchdog" ? whole(arg, value, 0, 1000000000L, o.watchdog) : whole(arg, value, 1, 99, o.priority))) return false;
    } else {
      o.input = arg;
    }
  }
  return true;
}

/// --realtime: SCHED_FIFO and locked memory where permitted; says on stderr what it got.
void enter_realtime(long priority) {
  sched_param param{};
  param.sched_priority = static_cast<int>(priority);
  if (sched_setscheduler(0, SCHED_FIFO, &param) == 0) {
    std::cerr << "device_loop: SCHED_FIFO priority " << priority << "\n";
  } else {
    std::cerr << "device_loop: SCHED_FIFO not permitted (" << std::strerror(errno) << "): normal priority\n";
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    std::cerr << "device_loop: memory locked (mlockall)\n";
  } else {
    std::cerr << "device_loop: mlockall not permitted (" << std::strerror(errno) << "): memory not locked\n";
  }
}

/// Absolute deadlines on CLOCK_MONOTONIC, one period apart (--realtime).
class Pacer {
 public:
  explicit Pacer(double period_s) : period_ns_(static_cast<long long>(period_s * 1e9 + 0.5)) { next_ = now_ns() + period_ns_; }
  /// After a cycle's output: a `late` one (an overrun, late() before its output) starts the
  /// deadlines again from now (no burst to catch up); else sleep until the deadline, the next one after it.
  void finish(bool late) {
    const long long now = now_ns();
    worst_ns_ = std::max(worst_ns_, now - (next_ - period_ns_));
    if (late) {
      ++overruns_;
      next_ = now + period_ns_;
      return;
    }
    timespec at{static_cast<time_t>(next_ / 1000000000LL), static_cast<long>(next_ % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR && g_signal == 0) {
    }
    next_ += period_ns_;
  }
  /// Whether the cycle under way is already past its deadline (its row's `overrun`).
  bool late() const { return now_ns() > next_; }
  long overruns() const { return overruns_; }
  double worst_s() const { return 1e-9 * static_cast<double>(worst_ns_); }

 private:
  static long long now_ns() {
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    return static_cast<long long>(t.tv_sec) * 1000000000LL + t.tv_nsec;
  }
  long long period_ns_;
  long long next_ = 0;
  long overruns_ = 0;
  long long worst_ns_ = 0;
};

/// The latched E-stop: set by the input or SIGUSR1, released only by an explicit reset (the
/// input's or SIGUSR2) while the input is not active.
class EStop {
 public:
  /// This cycle's state; notes each change in the log.
  bool update(const Inputs& in, DeviceIo& io) {
    const std::sig_atomic_t signals = g_estop_signals, resets = g_reset_signals;
    const bool by_signal = signals != seen_estop_, reset_signal = resets != seen_reset_;
    seen_estop_ = signals;
    seen_reset_ = resets;
    if (in.estop || by_signal) {
      if (!latched_) io.note(in.estop ? "estop: latched (input)" : "estop: latched (SIGUSR1)");
      latched_ = true;
    } else if (latched_ && (in.estop_reset || reset_signal)) {
      io.note(in.estop_reset ? "estop: released (input)" : "estop: released (SIGUSR2)");
      latched_ = false;
    }
    return latched_;
  }

 private:
  bool latched_ = false;
  std::sig_atomic_t seen_estop_ = 0, seen_reset_ = 0;
};

void install_signals() {
  // SIGINT and SIGTERM end the loop after the cycle under way (no SA_RESTART: a read waiting for
  // input returns at once), and the motors get zero duty.
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  // SIGUSR1 / SIGUSR2 (E-stop, its reset) act at the next cycle: a read they interrupt goes on.
  struct sigaction estop {};
  estop.sa_handler = on_estop;
  estop.sa_flags = SA_RESTART;
  sigemptyset(&estop.sa_mask);
  sigaction(SIGUSR1, &estop, nullptr);
  sigaction(SIGUSR2, &estop, nullptr);
}

/// The loop until the input ends or a signal stops it; the last time read in `t`.
void run(const Options& o, CsvIo& io, rt::Controller& controller, double& t) {
  // Buffers sized once: the loop below does not allocate.
  std::vector<double> readings(controller.joint_count()), targets(2 * controller.mechanism_count());
  std::vector<rt::Status> statuses(controller.mechanism_count());
  std::unique_ptr<Pacer> pacer;
  if (o.realtime) {
    enter_realtime(o.priority);
    pacer = std::make_unique<Pacer>(1.0 / controller.config().loop_rate_hz);
  }
  EStop estop;
  long stale = 0, cycles = 0;  // cycles in a row without new references
  bool any_fresh = false, was_latched = false;
  Inputs in;
  while (g_signal == 0 && io.read(in, readings.data(), targets.data())) {
    t = in.t_s;
    ++cycles;
    if (!in.fresh && !any_fresh) throw std::runtime_error("input: the first row brings no reference points");
    any_fresh = true;
    stale = in.fresh ? 0 : stale + 1;
    const bool latched = estop.update(in, io);
    if (latched || was_latched || stale > o.watchdog) controller.reset();  // no held command, no integral carried over
    was_latched = latched;
    const bool runs = !latched && stale <= o.watchdog;
    if (runs) {
      controller.cycle(readings.data(), io.kind(), targets.data());
      for (std::size_t k = 0; k < statuses.size(); ++k) statuses[k] = controller.mechanism(k).status;
    }
    const bool late = pacer && pacer->late();  // just before the output: the row's `overrun`
    if (runs) {
      io.write(t, controller.duties(), statuses.data(), late);
    } else {
      io.write_zero(t, latched ? "estop" : "stale", late);
    }
    if (pacer) pacer->finish(late);
  }
  if (pacer) {
    std::cerr << "device_loop: " << pacer->overruns() << " overruns in " << cycles << " cycles (longest cycle "
              << pacer->worst_s() * 1e3 << " ms, period " << 1e3 / controller.config().loop_rate_hz << " ms)\n";
  }
}
}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) return 2;
  install_signals();
  std::unique_ptr<CsvIo> io_owner;
  double t = 0.0;
  try {
    rt::Config config = rt::load_config_json(o.config);  // refuses a bad configuration, naming the key
    std::ifstream file;
    if (o.input != "-") {
      file.open(o.input);
      if (!file) throw std::runtime_error(o.input + ": cannot be read");
    }
    // Leaves out the stations the log lacks.
    ChannelMap channels;
    if (!o.channels.empty()) channels = read_channel_map(o.channels);
    lio::LinuxIoConfig linux_base;
    if (o.io != "linux" && (o.sysfs_root != "/" || o.iio_device != 0 || o.pwm_chip != 0 || o.estop_gpio >= 0)) {
      throw std::runtime_error("--sysfs-root, --iio-device, --pwm-chip and --estop-gpio are for --io linux");
    }
    if (o.io == "linux") {
      if (o.channels.empty() || !channels.has_gpio) {
        throw std::runtime_error("--io linux: needs --channels MAP.csv with the column direction_gpio");
      }
      linux_base.root = o.sysfs_root;
      linux_base.iio_device = static_cast<int>(o.iio_device);
      linux_base.pwm_chip = static_cast<int>(o.pwm_chip);
      linux_base.pwm_hz = config.pwm_hz;
      linux_base.adc_bits = config.adc_bits;
      linux_base.estop_gpio = static_cast<int>(o.estop_gpio);
    }
    io_owner = std::make_unique<CsvIo>(o.input == "-" ? std::cin : file, std::cout, config, o.realtime,
                                       o.channels.empty() ? nullptr : &channels, o.io == "linux" ? &linux_base : nullptr);
    rt::Controller controller(std::move(config));
    run(o, *io_owner, controller, t);
  } catch (const std::exception& e) {
    std::cerr << "device_loop: " << e.what() << "\n";
    if (io_owner) io_owner->stop(t, "error");
    return 2;
  }
  const int signal_number = g_signal;
  const bool stopped = io_owner->stop(t, signal_number == SIGINT ? "SIGINT" : signal_number == SIGTERM ? "SIGTERM" : "end of input");
  if (!stopped) return 2;  // the motors may still be driven: said on stderr
  return signal_number != 0 ? 128 + signal_number : 0;
}
