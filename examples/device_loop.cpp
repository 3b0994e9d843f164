// The device's control loop around fivebar::runtime (docs/runtime.md "Device loop"): the starting
// point of the device's ROS 2 node. It reads the exported configuration, then every period reads the
// joints and the reference points from an I/O backend, runs one cycle, and writes the duties.
//
//   device_loop CONFIG.json [IN.csv|-] [--realtime] [--watchdog N]
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

#include <signal.h>

#include <charconv>
#include <csignal>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "fivebar/runtime.hpp"

namespace rt = fivebar::runtime;

/// What the loop needs from the hardware (or its stand-in).
class DeviceIo {
 public:
  virtual ~DeviceIo() = default;
  /// The next sample: readings (joint order) and reference points (m, 2 per mechanism; `fresh`
  /// false when none came this cycle: `targets_m` is left as it was); false at the end.
  virtual bool read(double& t_s, double* readings, double* targets_m, bool& fresh) = 0;
  /// The duties (joint order) and statuses (mechanism order) of this cycle.
  virtual void write(double t_s, const double* duties, const rt::Status* statuses) = 0;
  virtual rt::Reading kind() const = 0;
  /// Zero duty to every motor: the loop's last output, whatever ends it (`why`: what did).
  virtual void stop(double t_s, const char* why) = 0;
};

/// CSV on streams: a recorded or piped log in, duties out.
class CsvIo : public DeviceIo {
 public:
  /// Reads the header; a station of `c` with no column in it is left out of `c` (a log of one
  /// station runs against the export of several, as `fivebar replay` reads it).
  CsvIo(std::istream& in, std::ostream& out, rt::Config& c) : in_(in), out_(out) {
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
    kind_ = at.count(first + "_counts") ? rt::Reading::counts : at.count(first + "_volts") ? rt::Reading::volts : rt::Reading::radians;
    const char* suffix = kind_ == rt::Reading::counts ? "_counts" : kind_ == rt::Reading::volts ? "_volts" : "_theta_rad";
    time_ = column("time_s");
    out_ << "time_s";
    for (const auto& s : c.stations)
      for (const auto& m : s.mechanisms) {
        for (const auto& j : m.joints) {
          reading_.push_back(column(j.name + suffix));
          out_ << "," << j.name << "_duty";
        }
        target_.push_back(column(s.name + "_" + m.name + "_x_ref_mm"));
        target_.push_back(column(s.name + "_" + m.name + "_y_ref_mm"));
      }
    for (const auto& s : c.stations)
      for (const auto& m : s.mechanisms) out_ << "," << s.name << "_" << m.name << "_status";
    out_ << "\n";
    out_.precision(17);
  }
  bool read(double& t, double* readings, double* targets, bool& fresh) override {
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
    t = cell(time_);
    for (std::size_t i = 0; i < reading_.size(); ++i) readings[i] = cell(reading_[i]);
    // Every reference cell empty: no new reference this cycle (else each must be a number).
    fresh = false;
    for (std::size_t i : target_) fresh = fresh || (i < cells.size() && !cells[i].empty());
    if (fresh)
      for (std::size_t i = 0; i < target_.size(); ++i) targets[i] = cell(target_[i]) / 1000.0;
    return true;
  }
  void write(double t, const double* duties, const rt::Status* statuses) override {
    out_ << t;
    for (std::size_t i = 0; i < reading_.size(); ++i) out_ << "," << duties[i];
    for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << "," << rt::to_string(statuses[k]);
    out_ << "\n";
    out_.flush();  // a pipe's reader (the motor driver's stand-in) sees every cycle at once
  }
  rt::Reading kind() const override { return kind_; }
  /// Zero duties with every status `stale` (the watchdog).
  void write_stale(double t) {
    out_ << t;
    for (std::size_t i = 0; i < reading_.size(); ++i) out_ << ",0";
    for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << ",stale";
    out_ << "\n";
    out_.flush();
  }
  void stop(double t, const char* why) override {
    out_ << "# stopped: " << why << "\n" << t;
    for (std::size_t i = 0; i < reading_.size(); ++i) out_ << ",0";
    for (std::size_t k = 0; k < target_.size() / 2; ++k) out_ << ",stopped";
    out_ << std::endl;
  }

 private:
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
  rt::Reading kind_ = rt::Reading::counts;
  std::size_t time_ = 0;
  std::size_t line_ = 0;  ///< 1-based line of the last line read
  std::vector<std::string> header_;
  std::vector<std::size_t> reading_, target_;
};

namespace {
volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_signal(int signal_number) { g_signal = signal_number; }
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: device_loop CONFIG.json [IN.csv|-] [--realtime] [--watchdog N]\n";
    return 2;
  }
  bool realtime = false;
  std::string input = "-";
  long watchdog = 10;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--realtime") {
      realtime = true;
    } else if (arg == "--watchdog") {
      const std::string value = i + 1 < argc ? argv[++i] : "";
      const auto r = std::from_chars(value.data(), value.data() + value.size(), watchdog);
      if (value.empty() || r.ec != std::errc() || r.ptr != value.data() + value.size() || watchdog < 0) {
        std::cerr << "device_loop: --watchdog " << value << ": expected a whole number of cycles >= 0\n";
        return 2;
      }
    } else {
      input = arg;
    }
  }
  // SIGINT and SIGTERM end the loop after the cycle under way (no SA_RESTART: a read waiting for
  // input returns at once), and the motors get zero duty.
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  std::unique_ptr<CsvIo> io_owner;
  double t = 0.0;
  try {
    rt::Config config = rt::load_config_json(argv[1]);  // refuses a bad configuration, naming the key
    std::ifstream file;
    if (input != "-") {
      file.open(input);
      if (!file) throw std::runtime_error(input + ": cannot be read");
    }
    io_owner = std::make_unique<CsvIo>(input == "-" ? std::cin : file, std::cout, config);  // leaves out the stations the log lacks
    CsvIo& io = *io_owner;
    rt::Controller controller(std::move(config));
    // Buffers sized once: the loop below does not allocate.
    std::vector<double> readings(controller.joint_count()), targets(2 * controller.mechanism_count());
    std::vector<rt::Status> statuses(controller.mechanism_count());
    const auto period = std::chrono::duration<double>(1.0 / controller.config().loop_rate_hz);
    auto next = std::chrono::steady_clock::now();
    long stale = 0;  // cycles in a row without new references
    bool fresh = false, any_fresh = false;
    while (g_signal == 0 && io.read(t, readings.data(), targets.data(), fresh)) {
      if (!fresh && !any_fresh) throw std::runtime_error("input: the first row brings no reference points");
      any_fresh = true;
      stale = fresh ? 0 : stale + 1;
      if (stale > watchdog) {
        controller.reset();  // no held command, no integral carried over the gap
        io.write_stale(t);
      } else {
        controller.cycle(readings.data(), io.kind(), targets.data());
        for (std::size_t k = 0; k < statuses.size(); ++k) statuses[k] = controller.mechanism(k).status;
        io.write(t, controller.duties(), statuses.data());
      }
      if (realtime) {
        next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
        std::this_thread::sleep_until(next);
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "device_loop: " << e.what() << "\n";
    if (io_owner) io_owner->stop(t, "error");
    return 2;
  }
  const int signal_number = g_signal;
  io_owner->stop(t, signal_number == SIGINT ? "SIGINT" : signal_number == SIGTERM ? "SIGTERM" : "end of input");
  return signal_number != 0 ? 128 + signal_number : 0;
}
