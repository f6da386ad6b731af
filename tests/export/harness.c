/* A firmware-like loop around the generated controller, compiled with gcc and
 * clang at C99 and -Werror and run under AddressSanitizer and UBSan
 * (tests/cli/export_cli_test.sh): a first-order plant, the tuned
 * configuration, manual/auto switches, gain and sample-time changes, a
 * non-finite input. Prints "harness ok" and exits 0, or names the failure. */
#include <stdio.h>

#include "pidlab_pid.h"

static int failures = 0;

static void check(int ok, const char *what, long k) {
  if (!ok) {
    ++failures;
    if (failures <= 5) printf("FAIL %s at step %ld\n", what, k);
  }
}

int main(void) {
  pidlab_pid pid;
  pidlab_pid_config config = pidlab_pid_tuned;
  pidlab_real y = (pidlab_real)0, u = (pidlab_real)0, r = (pidlab_real)1;
  volatile double zero = 0.0;
  long k;
  check(pidlab_pid_init(&pid, &config) == PIDLAB_PID_OK, "init with the tuned configuration", 0);
  config.dt_s = (pidlab_real)-1;
  check(pidlab_pid_init(&pid, &config) == PIDLAB_PID_INVALID_CONFIG, "init refuses dt < 0", 0);
  check(pid.config.dt_s > (pidlab_real)0, "a refused init leaves the controller", 0);
  for (k = 0; k < 20000; ++k) {
    pidlab_pid_status status;
    if (k == 3000) pidlab_pid_set_manual(&pid, (pidlab_real)0.25);
    if (k == 5000) pidlab_pid_set_auto(&pid);
    if (k == 7000) check(pidlab_pid_set_gains(&pid, pid.config.kp * (pidlab_real)1.5, pid.config.ki, pid.config.kd,
                                              pid.config.tf) == PIDLAB_PID_OK, "set_gains", k);
    if (k == 9000) check(pidlab_pid_set_sample_time(&pid, pid.config.dt_s * (pidlab_real)2) == PIDLAB_PID_OK,
                         "set_sample_time", k);
    if (k == 11000) check(pidlab_pid_set_setpoint_weights(&pid, (pidlab_real)0.5, (pidlab_real)0) == PIDLAB_PID_OK,
                          "set_setpoint_weights", k);
    if (k == 12000) r = (pidlab_real)-1;
    status = pidlab_pid_step(&pid, r, y, &u);
    check(status == PIDLAB_PID_OK || status == PIDLAB_PID_SATURATED, "step status", k);
    check(!pid.config.has_output_max || u <= pid.config.output_max, "u <= output_max", k);
    check(!pid.config.has_output_min || u >= pid.config.output_min, "u >= output_min", k);
    if (k >= 3000 && k < 5000) check(u == (pidlab_real)0.25 || pid.config.has_output_max || pid.config.has_output_min,
                                     "manual output", k);
    /* the plant y' = -y + u, explicit Euler at the controller's period */
    y = y + pid.config.dt_s * (u - y);
  }
  check(pidlab_pid_step(&pid, (pidlab_real)(zero / zero), y, &u) == PIDLAB_PID_INVALID_INPUT, "NaN refused", k);
  check(pidlab_pid_set_gains(&pid, (pidlab_real)-1, (pidlab_real)0, (pidlab_real)0, (pidlab_real)0) ==
            PIDLAB_PID_INVALID_CONFIG,
        "negative kp refused", k);
  pidlab_pid_reset(&pid);
  check(pid.integral == (pidlab_real)0, "reset", k);
  if (failures) return 1;
  printf("harness ok: y = %g after %ld steps\n", (double)y, k);
  return 0;
}
