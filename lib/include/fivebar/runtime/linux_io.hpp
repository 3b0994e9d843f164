#pragma once
/// The device's I/O through the Linux kernel's sysfs interfaces (docs/runtime.md "Linux I/O"): the
/// joints' ADC codes from the IIO subsystem, the motors' PWM from the PWM subsystem, each motor's
/// direction from a GPIO line (the sysfs GPIO interface). Target `fivebar_runtime_linux` (alias
/// fivebar::runtime_linux), part of the runtime package, Linux only; C++17 and POSIX, nothing else.
///
/// Every path lies under a configurable root (default "/"), so the tests run it against a scratch
/// folder laid out like the kernel's files:
///   <root>/sys/bus/iio/devices/iio:device<D>/in_voltage<K>_raw             read: the joint's ADC code
///   <root>/sys/class/pwm/pwmchip<C>/export, pwm<M>/{period,duty_cycle,polarity,enable}   written
///   <root>/sys/class/gpio/export, gpio<G>/{direction,value}                 written (the E-stop line's value read)
/// Per cycle: read() and write() open, read or write and close each file (as `cat` and `echo >`
/// do), with no allocation and no exception.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace fivebar::runtime::linux_io {

/// A setup the kernel's files refuse (a missing chip, an export that does not appear, a write
/// that fails): the message names the file and the system's reason.
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where one joint is wired (from the device loop's channel map).
struct JointWiring {
  int adc_channel = 0;         ///< in_voltage<adc_channel>_raw of the IIO device
  int pwm_channel = 0;         ///< pwm<pwm_channel> of the PWM chip
  int direction_gpio = 0;      ///< the GPIO line (sysfs number) giving the motor's direction
  double direction = 1.0;      ///< -1: the motor is wired reversed (the duty's sign is flipped)
  double offset_counts = 0.0;  ///< added to the ADC code before it is the joint's reading
};

struct LinuxIoConfig {
  std::string root = "/";  ///< the file system root of every path (a scratch folder in tests)
  int iio_device = 0;      ///< iio:device<N>
  int pwm_chip = 0;        ///< pwmchip<N>
  double pwm_hz = 0.0;     ///< the exported pwm_hz: period = round(1e9 / pwm_hz) ns
  int adc_bits = 0;        ///< the exported adc.bits: a code outside [0, 2^bits) is a failed reading
  std::vector<JointWiring> joints;  ///< in the runtime's joint order
  int estop_gpio = -1;     ///< an E-stop input line (sysfs number; value 1 = pressed), -1: none
};

/// The PWM period in ns for `pwm_hz` (round(1e9 / pwm_hz)); IoError unless it is in [1, 1e9].
long long pwm_period_ns(double pwm_hz);
/// The documented integer conversion of a duty in [-1, 1] (after the channel's direction):
/// duty_cycle = round(|duty| period_ns) ns (ties away from zero; |duty| > 1 is taken as 1, NaN as 0);
/// the direction line is 1 where the duty is negative, else 0.
long long duty_cycle_ns(double duty, long long period_ns);
int direction_value(double duty);

class LinuxIo {
 public:
  /// Sets every channel up: exports pwm<M> (where absent) and writes duty_cycle 0, period, polarity
  /// `normal`, enable 1; exports gpio<G> (where absent) and writes direction `low` (an output
  /// driven low); checks that every in_voltage<K>_raw exists. IoError naming the file otherwise.
  explicit LinuxIo(LinuxIoConfig config);

  /// Each joint's reading: the ADC code plus its offset; a read that fails, or that is not a whole
  /// number in [0, 2^bits), is NaN (a failed reading: the runtime's sensor fault). Returns how many
  /// failed.
  std::size_t read(double* readings) noexcept;
  /// Each joint's duty (runtime joint order) times its direction to its PWM channel and direction
  /// line (direction first). Every channel is attempted; false if a write failed (error() says which).
  bool write(const double* duties) noexcept;
  /// Zero duty on every channel (every one attempted); false if a write failed.
  bool write_zero() noexcept;
  /// The E-stop input line (estop_gpio): true when its value reads 1, and when it cannot be read
  /// or reads anything but 0 or 1 (fail-safe); false without a line.
  bool estop() noexcept;

  long long period_ns() const { return period_ns_; }
  /// The last failure: "FILE: reason".
  const char* error() const { return error_; }
  const LinuxIoConfig& config() const { return config_; }

 private:
  struct Paths {
    std::string adc, duty, direction_value;
  };
  bool put(const std::string& path, const char* text) noexcept;
  LinuxIoConfig config_;
  long long period_ns_ = 0;
  long long max_code_ = 0;
  std::vector<Paths> paths_;
  std::string estop_value_;  ///< gpio<estop_gpio>/value, empty without
  char error_[512] = {};
};

}  // namespace fivebar::runtime::linux_io
