// The C API (fivebar/runtime/c_api.h) over fivebar::runtime::Controller.

#include "fivebar/runtime/c_api.h"

#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "fivebar/runtime/controller.hpp"
#include "fivebar/runtime/json_config.hpp"

struct fivebar_runtime {
  fivebar::runtime::Controller controller;
  std::vector<std::string> joint_names;
};

namespace {

void copy_error(const char* what, char* error, size_t size) {
  if (error == nullptr || size == 0) return;
  std::strncpy(error, what, size - 1);
  error[size - 1] = '\0';
}

fivebar_runtime* make(fivebar::runtime::Config config, char* error, size_t size) {
  try {
    std::vector<std::string> names;
    for (const auto& s : config.stations)
      for (const auto& m : s.mechanisms)
        for (const auto& j : m.joints) names.push_back(j.name);
    return new fivebar_runtime{fivebar::runtime::Controller(std::move(config)), std::move(names)};
  } catch (const std::exception& e) {
    copy_error(e.what(), error, size);
  }
  return nullptr;
}

}  // namespace

extern "C" {

fivebar_runtime* fivebar_runtime_create_from_file(const char* path, char* error, size_t size) {
  if (path == nullptr) {
    copy_error("no path", error, size);
    return nullptr;
  }
  try {
    return make(fivebar::runtime::load_config_json(path), error, size);
  } catch (const std::exception& e) {
    copy_error(e.what(), error, size);
  }
  return nullptr;
}

fivebar_runtime* fivebar_runtime_create_from_json(const char* text, size_t length, char* error, size_t size) {
  if (text == nullptr) {
    copy_error("no text", error, size);
    return nullptr;
  }
  try {
    return make(fivebar::runtime::parse_config_json(std::string_view(text, length), "json"), error, size);
  } catch (const std::exception& e) {
    copy_error(e.what(), error, size);
  }
  return nullptr;
}

void fivebar_runtime_destroy(fivebar_runtime* r) { delete r; }

size_t fivebar_runtime_mechanism_count(const fivebar_runtime* r) { return r ? r->controller.mechanism_count() : 0; }
size_t fivebar_runtime_joint_count(const fivebar_runtime* r) { return r ? r->controller.joint_count() : 0; }

const char* fivebar_runtime_joint_name(const fivebar_runtime* r, size_t joint) {
  if (r == nullptr || joint >= r->joint_names.size()) return nullptr;
  return r->joint_names[joint].c_str();
}

double fivebar_runtime_loop_rate_hz(const fivebar_runtime* r) { return r ? r->controller.config().loop_rate_hz : 0.0; }

int fivebar_runtime_cycle(fivebar_runtime* r, const double* readings, int kind, const double* targets, double* duties,
                          int* statuses) {
  if (r == nullptr || readings == nullptr || duties == nullptr || kind < 0 || kind > 2) return -1;
  r->controller.cycle(readings, static_cast<fivebar::runtime::Reading>(kind), targets);
  const std::size_t n = r->controller.mechanism_count();
  std::memcpy(duties, r->controller.duties(), 2 * n * sizeof(double));
  if (statuses != nullptr) {
    for (std::size_t k = 0; k < n; ++k) statuses[k] = static_cast<int>(r->controller.mechanism(k).status);
  }
  return 0;
}

int fivebar_runtime_points(const fivebar_runtime* r, double* measured, double* commanded) {
  if (r == nullptr) return -1;
  for (std::size_t k = 0; k < r->controller.mechanism_count(); ++k) {
    const auto& m = r->controller.mechanism(k);
    for (std::size_t i = 0; i < 2; ++i) {
      if (measured) measured[2 * k + i] = m.point_measured[i];
      if (commanded) commanded[2 * k + i] = m.point_command[i];
    }
  }
  return 0;
}

int fivebar_runtime_joint_commands(const fivebar_runtime* r, double* theta) {
  if (r == nullptr || theta == nullptr) return -1;
  for (std::size_t k = 0; k < r->controller.mechanism_count(); ++k) {
    for (std::size_t j = 0; j < 2; ++j) theta[2 * k + j] = r->controller.mechanism(k).theta_command[j];
  }
  return 0;
}

int fivebar_runtime_joint_targets(const fivebar_runtime* r, double* theta) {
  if (r == nullptr || theta == nullptr) return -1;
  int limited = 0;
  for (std::size_t k = 0; k < r->controller.mechanism_count(); ++k) {
    const fivebar::runtime::MechanismState& st = r->controller.mechanism(k);
    for (std::size_t j = 0; j < 2; ++j) {
      theta[2 * k + j] = st.theta_follow[j];
      limited += st.command && st.theta_follow[j] != st.theta_command[j];
    }
  }
  return limited;
}

int fivebar_runtime_moved(const fivebar_runtime* r, double* moved) {
  if (r == nullptr || moved == nullptr) return -1;
  for (std::size_t k = 0; k < r->controller.mechanism_count(); ++k) moved[k] = r->controller.mechanism(k).moved;
  return 0;
}

size_t fivebar_runtime_station_count(const fivebar_runtime* r) { return r ? r->controller.config().stations.size() : 0; }

int fivebar_runtime_measured_clearance(const fivebar_runtime* r, size_t station, double* clearance, int* collision) {
  if (r == nullptr || clearance == nullptr || station >= r->controller.config().stations.size()) return -1;
  const fivebar::runtime::StationState& s = r->controller.station(station);
  *clearance = s.checked ? s.measured_clearance : 0.0;
  if (collision) *collision = s.checked && s.measured_collision ? 1 : 0;
  return s.checked ? 1 : 0;
}

#define FIVEBAR_STR2(x) #x
#define FIVEBAR_STR(x) FIVEBAR_STR2(x)
const char* fivebar_runtime_version(void) {
  return FIVEBAR_STR(FIVEBAR_RUNTIME_VERSION_MAJOR) "." FIVEBAR_STR(FIVEBAR_RUNTIME_VERSION_MINOR) "." FIVEBAR_STR(
      FIVEBAR_RUNTIME_VERSION_PATCH);
}

void fivebar_runtime_reset(fivebar_runtime* r) {
  if (r) r->controller.reset();
}

const char* fivebar_runtime_status_name(int status) {
  if (status < 0 || status > 5) return "unknown";
  return fivebar::runtime::to_string(static_cast<fivebar::runtime::Status>(status));
}

}  // extern "C"
