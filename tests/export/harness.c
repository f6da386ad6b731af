/* A firmware-like loop around the generated controller, compiled with gcc and
 * clang at C99 and -Werror and run under AddressSanitizer and UBSan
 * (tests/cli/export_cli_test.sh), for every scalar: a first-order plant
 * (simulated in double), the tuned configuration, manual/auto switches, gain,
 * weight and sample-time changes, refused values; floating point: a NaN
 * input; fixed point: inputs at the integer type's extremes, which must
 * saturate the output, not wrap it. Prints "harness ok" and exits 0, or names
 * the failure. */
#include <stdint.h>
#include <stdio.h>

#include "pidlab_pid.h"

#ifdef PIDLAB_Q_BITS
typedef pidlab_q value;
typedef double parameter;
#define TO_VALUE_IN(x) PIDLAB_INPUT_Q(x)
#define TO_VALUE_OUT(x) PIDLAB_OUTPUT_Q(x)
#define FROM_VALUE_OUT(q) ((double)(q)*PIDLAB_OUTPUT_FULL_SCALE / (double)((int64_t)1 << PIDLAB_Q_BITS))
#define HAS_MIN(c) 1
#define HAS_MAX(c) 1
#else
typedef pidlab_real value;
typedef pidlab_real parameter;
#define TO_VALUE_IN(x) ((pidlab_real)(x))
#define TO_VALUE_OUT(x) ((pidlab_real)(x))
#define FROM_VALUE_OUT(u) ((double)(u))
#define HAS_MIN(c) ((c).has_output_min)
#define HAS_MAX(c) ((c).has_output_max)
#endif

static int failures = 0;

static void check(int ok, const char *what, long k) {
  if (!ok) {
    ++failures;
    if (failures <= 5) printf("FAIL %s at step %ld\n", what, k);
  }
}

static int inside(const pidlab_pid *pid, double u) {
  const double slack = 1e-6 * (pid->config.output_max - pid->config.output_min);
  return (!HAS_MAX(pid->config) || u <= (double)pid->config.output_max + slack) &&
         (!HAS_MIN(pid->config) || u >= (double)pid->config.output_min - slack);
}

static void run(pidlab_pid *pid) {
  double y = 0.0, r = 0.5;
  value u = TO_VALUE_OUT(0.0);
  long k;
  for (k = 0; k < 20000; ++k) {
    pidlab_pid_status status;
    if (k == 3000) check(pidlab_pid_set_manual(pid, TO_VALUE_OUT(0.25)) == PIDLAB_PID_OK, "set_manual", k);
    if (k == 5000) pidlab_pid_set_auto(pid);
    if (k == 7000)
      check(pidlab_pid_set_gains(pid, (parameter)(pid->config.kp * 0.75), pid->config.ki, pid->config.kd,
                                 pid->config.tf) == PIDLAB_PID_OK,
            "set_gains", k);
    if (k == 9000)
      check(pidlab_pid_set_sample_time(pid, (parameter)(pid->config.dt_s * 1.5)) == PIDLAB_PID_OK,
            "set_sample_time", k);
    if (k == 11000)
      check(pidlab_pid_set_setpoint_weights(pid, (parameter)0.5, (parameter)0) == PIDLAB_PID_OK,
            "set_weights", k);
    if (k == 12000) r = -0.5;
    status = pidlab_pid_step(pid, TO_VALUE_IN(r), TO_VALUE_IN(y), &u);
    check(status == PIDLAB_PID_OK || status == PIDLAB_PID_SATURATED, "step status", k);
    check(inside(pid, FROM_VALUE_OUT(u)), "u inside the output limits", k);
    if (k >= 3000 && k < 5000 && inside(pid, 0.25))
      check(FROM_VALUE_OUT(u) > 0.2499 && FROM_VALUE_OUT(u) < 0.2501, "manual output", k);
    /* the plant y' = -y + u, explicit Euler at the controller's period */
    y = y + (double)pid->config.dt_s * (FROM_VALUE_OUT(u) - y);
  }
  check(pidlab_pid_set_gains(pid, (parameter)-1, (parameter)1, (parameter)0, (parameter)0) ==
            PIDLAB_PID_INVALID_CONFIG,
        "gains that differ in sign refused", k);
#ifndef PIDLAB_Q_BITS
  /* double and float: a reverse-acting PID's gains, all <= 0, are taken */
  check(pidlab_pid_set_gains(pid, (parameter)-1, (parameter)-0.5, (parameter)0, (parameter)0) == PIDLAB_PID_OK,
        "gains all <= 0 (reverse acting) taken", k);
#endif
  check(pidlab_pid_set_sample_time(pid, (parameter)0) == PIDLAB_PID_INVALID_CONFIG, "dt = 0 refused", k);
#ifdef PIDLAB_Q_BITS
  {
    /* r at the type's top, y at its bottom: far outside the declared range,
     * the output must sit at its upper limit, not wrap below it. */
    const pidlab_q top = (pidlab_q)((((int64_t)1) << PIDLAB_Q_BITS) - 1);
    const pidlab_q bottom = (pidlab_q)(-top - 1);
    for (k = 0; k < 100; ++k) {
      pidlab_pid_step(pid, top, bottom, &u);
      check(inside(pid, FROM_VALUE_OUT(u)), "extreme inputs: u inside the limits", k);
      if (k > 2 && pid->config.kp > 0.0)
        check(FROM_VALUE_OUT(u) > pid->config.output_max - 1e-6 * pid->config.output_max,
              "extreme inputs saturate high", k);
    }
    pidlab_pid_step(pid, bottom, top, &u);
    check(inside(pid, FROM_VALUE_OUT(u)), "extreme inputs reversed: u inside the limits", k);
  }
#else
  {
    volatile double zero = 0.0;
    check(pidlab_pid_step(pid, (pidlab_real)(zero / zero), TO_VALUE_IN(y), &u) == PIDLAB_PID_INVALID_INPUT,
          "NaN refused", k);
  }
#endif
  printf("y = %g after %ld steps; ", y, 20000L);
}

int main(void) {
  pidlab_pid pid;
  pidlab_pid_config config = pidlab_pid_tuned;
  check(pidlab_pid_init(&pid, &config) == PIDLAB_PID_OK, "init with the tuned configuration", 0);
  config.dt_s = (parameter)-1;
  check(pidlab_pid_init(&pid, &config) == PIDLAB_PID_INVALID_CONFIG, "init refuses dt < 0", 0);
  check(pid.config.dt_s > (parameter)0, "a refused init leaves the controller", 0);
  run(&pid);
  pidlab_pid_reset(&pid);
  check(pid.integral == 0, "reset", 0);
  if (failures) return 1;
  printf("harness ok\n");
  return 0;
}
