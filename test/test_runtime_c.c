/* The runtime's C API (fivebar/runtime/c_api.h) from a C99 program: the exported JSON of the paper's
 * device (argv[1]), the joint names, sensor faults at the rails, the PID's sign and symmetry about
 * the commanded angles, the collision figures, the slew limit's targets, the version, a refused configuration naming its key,
 * and NULL handles. With a second argument, a fixed pattern's duties written exactly (for the
 * comparison of builds). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fivebar/runtime/c_api.h"

static int failures = 0;
#define CHECK(cond)                                                   \
  do {                                                                \
    if (!(cond)) {                                                    \
      fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                     \
    }                                                                 \
  } while (0)

int main(int argc, char** argv) {
  char error[512] = {0};
  fivebar_runtime* rt;
  size_t n, m, i;
  double readings[8], targets[8], duties[8], commands[8], measured[8];
  int statuses[4];
  if (argc < 2) {
    fprintf(stderr, "usage: %s EXPORTED.json\n", argv[0]);
    return 2;
  }
  rt = fivebar_runtime_create_from_file(argv[1], error, sizeof error);
  if (rt == NULL) {
    fprintf(stderr, "create: %s\n", error);
    return 1;
  }
  n = fivebar_runtime_joint_count(rt);
  m = fivebar_runtime_mechanism_count(rt);
  CHECK(n == 8 && m == 4);
  CHECK(strcmp(fivebar_runtime_joint_name(rt, 0), "index_lower_theta1") == 0);
  CHECK(strcmp(fivebar_runtime_joint_name(rt, 7), "thumb_upper_theta2") == 0);
  CHECK(fivebar_runtime_joint_name(rt, 8) == NULL);
  CHECK(fivebar_runtime_loop_rate_hz(rt) == 100.0);

  /* Targets: the paper's target centres (index (6.25, 15.5) mm, thumb (6.25, 17.5) mm), tactors 6 mm apart. */
  targets[0] = 6.25e-3, targets[1] = 12.5e-3, targets[2] = 6.25e-3, targets[3] = 18.5e-3;
  targets[4] = 6.25e-3, targets[5] = 14.5e-3, targets[6] = 6.25e-3, targets[7] = 20.5e-3;

  /* ADC codes at the rails: every mechanism faults, every duty is zero. */
  for (i = 0; i < n; ++i) readings[i] = (i % 2) ? 65535.0 : 0.0;
  CHECK(fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_COUNTS, targets, duties, statuses) == 0);
  for (i = 0; i < m; ++i) CHECK(statuses[i] == FIVEBAR_STATUS_SENSOR_FAULT);
  for (i = 0; i < n; ++i) CHECK(duties[i] == 0.0);
  CHECK(strcmp(fivebar_runtime_status_name(statuses[0]), "sensor_fault") == 0);

  /* Joints 0.01 rad short of their commands: every duty positive, the same for both joints of a
   * mechanism (one set of gains per mechanism in the showcase), and the measured points exist. */
  CHECK(fivebar_runtime_joint_commands(rt, commands) == 0);
  for (i = 0; i < n; ++i) readings[i] = 0.0;
  fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
  fivebar_runtime_joint_commands(rt, commands);
  for (i = 0; i < n; ++i) readings[i] = commands[i] - 0.01;
  fivebar_runtime_reset(rt);
  CHECK(fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses) == 0);
  for (i = 0; i < m; ++i) CHECK(statuses[i] == FIVEBAR_STATUS_OK);
  for (i = 0; i < n; ++i) CHECK(duties[i] > 0.0 && duties[i] <= 1.0 && isfinite(duties[i]));
  for (i = 0; i < m; ++i) CHECK(fabs(duties[2 * i] - duties[2 * i + 1]) < 1e-12);
  CHECK(fivebar_runtime_points(rt, measured, NULL) == 0);
  for (i = 0; i < 2 * m; ++i) CHECK(isfinite(measured[i]) && fabs(measured[i]) < 0.1);
  /* Mirrored error, mirrored duty (first sample after a reset: no derivative). */
  for (i = 0; i < n; ++i) readings[i] = commands[i] + 0.01;
  {
    double up[8];
    memcpy(up, duties, sizeof up);
    fivebar_runtime_reset(rt);
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    for (i = 0; i < n; ++i) CHECK(duties[i] == -up[i]);
  }

  /* The collision figures: both stations measured (tactors 6 mm apart: clear), nothing moved; a
   * lower target on the upper one is moved by the priority rule, and the distance it reports is the
   * distance between the target and the commanded point. */
  {
    double clearance = -1.0, moved[4], commanded[8], dx, dy;
    int collision = -1;
    for (i = 0; i < n; ++i) readings[i] = commands[i];
    fivebar_runtime_reset(rt);
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    CHECK(fivebar_runtime_station_count(rt) == 2);
    CHECK(fivebar_runtime_measured_clearance(rt, 0, &clearance, &collision) == 1);
    CHECK(clearance > 0.0 && clearance < 0.01 && collision == 0);
    CHECK(fivebar_runtime_measured_clearance(rt, 2, &clearance, NULL) == -1);
    CHECK(fivebar_runtime_measured_clearance(NULL, 0, &clearance, NULL) == -1);
    CHECK(fivebar_runtime_moved(rt, moved) == 0);
    for (i = 0; i < m; ++i) CHECK(moved[i] == 0.0);
    targets[1] = targets[3]; /* index lower onto index upper */
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    CHECK(statuses[0] == FIVEBAR_STATUS_MOVED_BY_PRIORITY);
    CHECK(fivebar_runtime_moved(rt, moved) == 0);
    fivebar_runtime_points(rt, NULL, commanded);
    dx = commanded[0] - targets[0], dy = commanded[1] - targets[1];
    CHECK(moved[0] > 0.0 && fabs(moved[0] - sqrt(dx * dx + dy * dy)) < 1e-12);
    CHECK(fivebar_runtime_moved(rt, NULL) == -1);
    targets[1] = 12.5e-3;
  }
  /* The slew limit: joints 0.5 rad short of their commands (more than the showcase's exported
   * 5.996 rad/s x 10 ms per cycle) follow targets that start at the readings and move exactly
   * max_velocity / loop_rate_hz toward the commands per cycle; a 0.01 rad gap is closed at once. */
  {
    double follow[8];
    const double step = 5.9959862654712 / 100.0; /* joint_limits.*.max_velocity of the export / loop_rate_hz */
    for (i = 0; i < n; ++i) readings[i] = commands[i] - 0.5;
    fivebar_runtime_reset(rt);
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    CHECK(fivebar_runtime_joint_targets(rt, follow) == (int)n);
    for (i = 0; i < n; ++i) CHECK(fabs(follow[i] - (readings[i] + step)) < 1e-12);
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    fivebar_runtime_joint_targets(rt, follow);
    for (i = 0; i < n; ++i) CHECK(fabs(follow[i] - (readings[i] + 2.0 * step)) < 1e-12);
    for (i = 0; i < n; ++i) readings[i] = commands[i] - 0.01;
    fivebar_runtime_reset(rt);
    fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
    CHECK(fivebar_runtime_joint_targets(rt, follow) == 0);
    for (i = 0; i < n; ++i) CHECK(follow[i] == commands[i]);
    CHECK(fivebar_runtime_joint_targets(rt, NULL) == -1);
    CHECK(fivebar_runtime_joint_targets(NULL, follow) == -1);
  }
  /* The version: the header's. */
  {
    char expected[32];
    snprintf(expected, sizeof expected, "%d.%d.%d", FIVEBAR_RUNTIME_VERSION_MAJOR, FIVEBAR_RUNTIME_VERSION_MINOR,
             FIVEBAR_RUNTIME_VERSION_PATCH);
    CHECK(strcmp(fivebar_runtime_version(), expected) == 0);
  }

  /* Bad handles and arguments. */
  CHECK(fivebar_runtime_cycle(NULL, readings, 0, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_cycle(rt, NULL, 0, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_cycle(rt, readings, 7, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_joint_count(NULL) == 0);
  fivebar_runtime_destroy(rt);

  /* A refused configuration names its key. */
  {
    const char* bad = "{\"n\": {\"ros__parameters\": {\"fivebar\": {\"design\": \"d\", \"design_hash\": \"h\", \"hash_algorithm\": \"a\", \"tool_version\": \"v\", \"format_version\": 1, \"units\": \"SI\"}, \"adc\": {}}}}";
    rt = fivebar_runtime_create_from_json(bad, strlen(bad), error, sizeof error);
    CHECK(rt == NULL);
    CHECK(strstr(error, "loop_rate_hz: missing key") != NULL);
  }
  /* With a second argument: 2000 cycles of a fixed pattern (targets turning about the station
   * centres, the lower ones crossing the upper ones every few cycles so that the priority rule runs,
   * readings the last commands plus a ripple) and every duty, status and distance moved written to
   * that file as exact hexadecimal floats: another build (aarch64 under qemu) must write the same
   * bytes (test/runtime_package/aarch64.sh). */
  if (argc > 2) {
    FILE* out = fopen(argv[2], "w");
    int k;
    double moved[4];
    CHECK(out != NULL);
    rt = fivebar_runtime_create_from_file(argv[1], error, sizeof error);
    CHECK(rt != NULL);
    if (out != NULL && rt != NULL) {
      for (i = 0; i < n; ++i) commands[i] = 0.0;
      for (k = 0; k < 2000; ++k) {
        const double phi = 0.0123 * k, r = 1e-3 * (1 + k % 7);
        targets[0] = 6.25e-3 + r * cos(3 * phi), targets[1] = 15.5e-3 - 3e-3 + 4e-3 * sin(phi);
        targets[2] = 6.25e-3 + 1e-3 * cos(phi), targets[3] = 15.5e-3 + 1.5e-3 * sin(2 * phi);
        targets[4] = 6.25e-3 + r * sin(phi), targets[5] = 17.5e-3 - 2e-3 + 3e-3 * cos(phi);
        targets[6] = 6.25e-3 - 1e-3 * sin(phi), targets[7] = 17.5e-3 + 1e-3 * cos(3 * phi);
        for (i = 0; i < n; ++i) readings[i] = commands[i] + 0.02 * sin(0.7 * k + (double)i);
        fivebar_runtime_cycle(rt, readings, FIVEBAR_READING_RADIANS, targets, duties, statuses);
        fivebar_runtime_joint_commands(rt, commands);
        fivebar_runtime_moved(rt, moved);
        for (i = 0; i < n; ++i) fprintf(out, "%a ", duties[i]);
        for (i = 0; i < m; ++i) fprintf(out, "%d %a ", statuses[i], moved[i]);
        fprintf(out, "\n");
      }
    }
    if (out != NULL) fclose(out);
    fivebar_runtime_destroy(rt);
  }
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("runtime C API: all checks passed\n");
  return failures ? 1 : 0;
}
