// The device's I/O through the kernel's sysfs files (fivebar/runtime/linux_io.hpp,
// docs/runtime.md "Linux I/O").

#include "fivebar/runtime/linux_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

namespace fivebar::runtime::linux_io {

namespace {

std::string join(const std::string& root, const std::string& rest) {
  if (root.empty()) return "/" + rest;
  return root.back() == '/' ? root + rest : root + "/" + rest;
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace

long long pwm_period_ns(double pwm_hz) {
  const double ns = 1e9 / pwm_hz;
  if (!(pwm_hz > 0.0) || !(ns >= 1.0 && ns <= 1e9)) {
    throw IoError("pwm_hz " + std::to_string(pwm_hz) + ": the PWM period must be within [1 ns, 1 s]");
  }
  return std::llround(ns);
}

long long duty_cycle_ns(double duty, long long period_ns) {
  const double a = std::fabs(duty);
  if (!(a == a)) return 0;  // NaN: no drive
  return std::llround((a > 1.0 ? 1.0 : a) * static_cast<double>(period_ns));
}

int direction_value(double duty) { return duty < 0.0 ? 1 : 0; }

bool LinuxIo::put(const std::string& path, const char* text) noexcept {
  const int fd = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);  // hygiene: allowed (sysfs attribute)
  const std::size_t n = std::strlen(text);
  bool ok = fd >= 0;
  int err = errno;
  if (ok) {
    const ssize_t w = ::write(fd, text, n);
    err = errno;
    ok = w == static_cast<ssize_t>(n);
    if (w >= 0 && !ok) err = EIO;
    if (::close(fd) != 0 && ok) {
      ok = false;
      err = errno;
    }
  }
  if (!ok) std::snprintf(error_, sizeof error_, "%s: %s", path.c_str(), std::strerror(err));
  return ok;
}

LinuxIo::LinuxIo(LinuxIoConfig config) : config_(std::move(config)) {
  period_ns_ = pwm_period_ns(config_.pwm_hz);
  if (config_.adc_bits < 1 || config_.adc_bits > 31) throw IoError("adc.bits " + std::to_string(config_.adc_bits) + ": expected 1 to 31");
  max_code_ = (1LL << config_.adc_bits) - 1;
  const std::string iio = join(config_.root, "sys/bus/iio/devices/iio:device" + std::to_string(config_.iio_device));
  const std::string chip = join(config_.root, "sys/class/pwm/pwmchip" + std::to_string(config_.pwm_chip));
  const std::string gpio = join(config_.root, "sys/class/gpio");
  const auto must = [&](const std::string& path, const std::string& text) {
    if (!put(path, text.c_str())) throw IoError(error_);
  };
  // A channel not yet exported: write its number to `export`; the kernel creates its folder.
  const auto exported = [&](const std::string& dir, const std::string& export_file, int number) {
    if (exists(dir)) return;
    must(export_file, std::to_string(number));
    if (!exists(dir)) throw IoError(dir + ": not there after writing " + std::to_string(number) + " to " + export_file);
  };
  if (!exists(chip)) throw IoError(chip + ": no such PWM chip");
  for (const JointWiring& j : config_.joints) {
    Paths p;
    p.adc = iio + "/in_voltage" + std::to_string(j.adc_channel) + "_raw";
    if (!exists(p.adc)) throw IoError(p.adc + ": no such ADC channel");
    const std::string pwm = chip + "/pwm" + std::to_string(j.pwm_channel);
    exported(pwm, chip + "/export", j.pwm_channel);
    p.duty = pwm + "/duty_cycle";
    must(p.duty, "0");  // first: a period shorter than the duty in place is refused by the kernel
    must(pwm + "/period", std::to_string(period_ns_));
    must(pwm + "/polarity", "normal");
    must(pwm + "/enable", "1");
    const std::string line = gpio + "/gpio" + std::to_string(j.direction_gpio);
    exported(line, gpio + "/export", j.direction_gpio);
    must(line + "/direction", "low");  // an output, driven low from the start
    p.direction_value = line + "/value";
    paths_.push_back(std::move(p));
  }
  if (config_.estop_gpio >= 0) {
    const std::string line = gpio + "/gpio" + std::to_string(config_.estop_gpio);
    exported(line, gpio + "/export", config_.estop_gpio);
    must(line + "/direction", "in");
    estop_value_ = line + "/value";
  }
}

bool LinuxIo::estop() noexcept {
  if (estop_value_.empty()) return false;
  char text[16];
  ssize_t n = -1;
  const int fd = ::open(estop_value_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    n = ::read(fd, text, sizeof text);
    ::close(fd);
  }
  // Only a clean "0" releases: a failed read or any other text is a pressed E-stop.
  return !(n >= 1 && text[0] == '0' && (n == 1 || text[1] == '\n'));
}

std::size_t LinuxIo::read(double* readings) noexcept {
  std::size_t failed = 0;
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    char text[64];
    ssize_t n = -1;
    const int fd = ::open(paths_[i].adc.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      n = ::read(fd, text, sizeof text - 1);
      ::close(fd);
    }
    long long code = -1;
    bool ok = n > 0;
    if (ok) {
      std::size_t len = static_cast<std::size_t>(n);
      while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == ' ')) --len;
      const auto r = std::from_chars(text, text + len, code);
      ok = len > 0 && r.ec == std::errc() && r.ptr == text + len && code >= 0 && code <= max_code_;
    }
    readings[i] = ok ? static_cast<double>(code) + config_.joints[i].offset_counts : std::nan("");
    failed += ok ? 0 : 1;
  }
  return failed;
}

bool LinuxIo::write(const double* duties) noexcept {
  bool ok = true;
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    const double d = duties[i] * config_.joints[i].direction;
    char text[32];
    std::snprintf(text, sizeof text, "%d", direction_value(d));
    ok = put(paths_[i].direction_value, text) && ok;
    std::snprintf(text, sizeof text, "%lld", duty_cycle_ns(d, period_ns_));
    ok = put(paths_[i].duty, text) && ok;
  }
  return ok;
}

bool LinuxIo::write_zero() noexcept {
  bool ok = true;
  for (const Paths& p : paths_) ok = put(p.duty, "0") && ok;
  return ok;
}

}  // namespace fivebar::runtime::linux_io
