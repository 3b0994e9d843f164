/* The runtime's C API (fivebar/runtime/c_api.h) from a C99 program: the exported JSON of the paper's
 * device (argv[1]), the joint names, sensor faults at the rails, the PID's sign and symmetry about
 * the commanded angles, a refused configuration naming its key, and NULL handles. */
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

  /* Bad handles and arguments. */
  CHECK(fivebar_runtime_cycle(NULL, readings, 0, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_cycle(rt, NULL, 0, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_cycle(rt, readings, 7, targets, duties, statuses) == -1);
  CHECK(fivebar_runtime_joint_count(NULL) == 0);
  fivebar_runtime_destroy(rt);

  /* A refused configuration names its key. */
  {
    const char* bad = "{\"n\": {\"ros__parameters\": {\"adc\": {}}}}";
    rt = fivebar_runtime_create_from_json(bad, strlen(bad), error, sizeof error);
    CHECK(rt == NULL);
    CHECK(strstr(error, "loop_rate_hz: missing key") != NULL);
  }
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("runtime C API: all checks passed\n");
  return failures ? 1 : 0;
}
