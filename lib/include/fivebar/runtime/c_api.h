/* The device's control cycle for C, ctypes, ROS 2 nodes and firmware (fivebar/runtime/controller.hpp,
 * docs/runtime.md): an opaque handle and plain arrays. Every function is safe to call with a NULL
 * handle (it returns an error or 0). No function allocates or throws after fivebar_runtime_create_*. */
#ifndef FIVEBAR_RUNTIME_C_API_H
#define FIVEBAR_RUNTIME_C_API_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The version of this header; fivebar_runtime_version() gives the library's (the same when they
 * match). */
#define FIVEBAR_RUNTIME_VERSION_MAJOR 0
#define FIVEBAR_RUNTIME_VERSION_MINOR 1
#define FIVEBAR_RUNTIME_VERSION_PATCH 0

typedef struct fivebar_runtime fivebar_runtime;

/* What the readings are (fivebar::runtime::Reading). */
enum fivebar_reading { FIVEBAR_READING_COUNTS = 0, FIVEBAR_READING_VOLTS = 1, FIVEBAR_READING_RADIANS = 2 };

/* Per mechanism and cycle (fivebar::runtime::Status). */
enum fivebar_status {
  FIVEBAR_STATUS_OK = 0,
  FIVEBAR_STATUS_MOVED_BY_PRIORITY = 1,
  FIVEBAR_STATUS_UNREACHABLE = 2,
  FIVEBAR_STATUS_SINGULAR = 3,
  FIVEBAR_STATUS_LIMIT = 4,
  FIVEBAR_STATUS_SENSOR_FAULT = 5
};

/* From the JSON file `fivebar export` writes. NULL on failure, with the message (naming the key)
 * copied into `error` (at most error_size bytes, NUL-terminated) when error is not NULL. */
fivebar_runtime* fivebar_runtime_create_from_file(const char* path, char* error, size_t error_size);
/* From the JSON text itself (`length` bytes). */
fivebar_runtime* fivebar_runtime_create_from_json(const char* text, size_t length, char* error, size_t error_size);
void fivebar_runtime_destroy(fivebar_runtime* runtime);

size_t fivebar_runtime_mechanism_count(const fivebar_runtime* runtime);
size_t fivebar_runtime_joint_count(const fivebar_runtime* runtime);
/* `<station>_<mechanism>_theta<1|2>` of joint `joint` (export order); NULL when out of range. */
const char* fivebar_runtime_joint_name(const fivebar_runtime* runtime, size_t joint);
double fivebar_runtime_loop_rate_hz(const fivebar_runtime* runtime);

/* One cycle: `readings` joint_count values of kind `kind`, `targets_m` 2 per mechanism (x, y, m).
 * Writes joint_count duties into `duties` and, when not NULL, mechanism_count statuses into
 * `statuses`. Returns 0, or -1 for a NULL handle, readings or duties pointer or an unknown kind. */
int fivebar_runtime_cycle(fivebar_runtime* runtime, const double* readings, int kind, const double* targets_m,
                          double* duties, int* statuses);
/* Measured (FK) and commanded tactor points of the last cycle, 2 per mechanism (m); NULL to skip. */
int fivebar_runtime_points(const fivebar_runtime* runtime, double* measured_m, double* commanded_m);
/* Commanded joint angles of the last cycle, joint_count values (rad, on each joint's branch). */
int fivebar_runtime_joint_commands(const fivebar_runtime* runtime, double* theta_rad);
/* The joint targets the PIDs followed in the last cycle (the slew limit: the commands approached at
 * most max_velocity / loop_rate_hz per cycle; 0 for a mechanism with zero duty), joint_count values
 * (rad). Returns the number of joints still short of their command (slew-limited), or -1 for a
 * NULL handle or pointer. */
int fivebar_runtime_joint_targets(const fivebar_runtime* runtime, double* theta_rad);
/* The priority rule's distance moved per mechanism of the last cycle (m; 0 unless its status is
 * moved_by_priority), mechanism_count values. Returns 0, or -1 for a NULL handle or pointer. */
int fivebar_runtime_moved(const fivebar_runtime* runtime, double* moved_m);
/* The measured clearance of station `station` (export order) between its two mechanisms' outlines
 * in the last cycle (m; negative: overlap). Returns 1 when measured (both mechanisms, the collision
 * geometry and both measured poses), 0 when not (then *clearance_m is 0), -1 for a NULL handle or
 * pointer or a station out of range. `collision` (when not NULL): 1 when below min_clearance. */
int fivebar_runtime_measured_clearance(const fivebar_runtime* runtime, size_t station, double* clearance_m,
                                       int* collision);
size_t fivebar_runtime_station_count(const fivebar_runtime* runtime);
void fivebar_runtime_reset(fivebar_runtime* runtime);
/* The runtime's version, "MAJOR.MINOR.PATCH" (FIVEBAR_RUNTIME_VERSION_*: the package's). */
const char* fivebar_runtime_version(void);
/* "ok", "moved_by_priority", ...; "unknown" for other values. */
const char* fivebar_runtime_status_name(int status);

#ifdef __cplusplus
}
#endif

#endif /* FIVEBAR_RUNTIME_C_API_H */
