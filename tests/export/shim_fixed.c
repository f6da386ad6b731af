/* The generated fixed-point controller behind a double interface, for
 * tests/export_test.cc (see shim_real.c): values are quantized to the
 * module's Q format on the way in and read back on the way out. */
#include <stdlib.h>

#include "pidlab_pid.h"

typedef struct {
  double kp, ki, kd, tf, b, c, dt_s;
  int has_output_min;
  double output_min;
  int has_output_max;
  double output_max;
  int anti_windup;
  double back_calculation_gain;
  int integral;
  double setpoint_filter_s;
} shim_config;

static double shim_two_n(void) { return (double)((int64_t)1 << PIDLAB_Q_BITS); }

static pidlab_q shim_q(double x, double full_scale) {
  double q = x / full_scale * shim_two_n();
  const double top = shim_two_n() - 1.0;
  q = q < 0 ? q - 0.5 : q + 0.5;
  if (q > top) q = top;
  if (q < -shim_two_n()) q = -shim_two_n();
  return (pidlab_q)q;
}

double shim_quantize_input(double x) {
  return (double)shim_q(x, PIDLAB_INPUT_FULL_SCALE) * PIDLAB_INPUT_FULL_SCALE / shim_two_n();
}
double shim_quantize_output(double x) {
  return (double)shim_q(x, PIDLAB_OUTPUT_FULL_SCALE) * PIDLAB_OUTPUT_FULL_SCALE / shim_two_n();
}
double shim_output_lsb(void) { return PIDLAB_OUTPUT_FULL_SCALE / shim_two_n(); }
int shim_q_bits(void) { return PIDLAB_Q_BITS; }
/* The raw step: pidlab_q in and out, for the wrap test. */
int shim_step_raw(void *pid, long r, long y, long *u) {
  pidlab_q out = 0;
  int status = (int)pidlab_pid_step((pidlab_pid *)pid, (pidlab_q)r, (pidlab_q)y, &out);
  *u = (long)out;
  return status;
}

void *shim_new(const shim_config *s) {
  pidlab_pid_config c;
  pidlab_pid *pid = (pidlab_pid *)malloc(sizeof(pidlab_pid));
  if (!pid) return NULL;
  c.kp = s->kp;
  c.ki = s->ki;
  c.kd = s->kd;
  c.tf = s->tf;
  c.setpoint_weight_b = s->b;
  c.setpoint_weight_c = s->c;
  c.setpoint_filter_s = s->setpoint_filter_s;
  c.dt_s = s->dt_s;
  c.output_min = s->output_min;
  c.output_max = s->output_max;
  c.anti_windup = (pidlab_anti_windup)s->anti_windup;
  c.back_calculation_gain = s->back_calculation_gain;
  c.integral = (pidlab_integral_rule)s->integral;
  if (!s->has_output_min || !s->has_output_max || pidlab_pid_init(pid, &c) != PIDLAB_PID_OK) {
    free(pid);
    return NULL;
  }
  return pid;
}

void *shim_new_tuned(void) {
  pidlab_pid *pid = (pidlab_pid *)malloc(sizeof(pidlab_pid));
  if (pid && pidlab_pid_init(pid, &pidlab_pid_tuned) != PIDLAB_PID_OK) {
    free(pid);
    return NULL;
  }
  return pid;
}

void shim_free(void *pid) { free(pid); }

int shim_step(void *pid, double r, double y, double *u) {
  pidlab_q out = 0;
  int status = (int)pidlab_pid_step((pidlab_pid *)pid, shim_q(r, PIDLAB_INPUT_FULL_SCALE),
                                    shim_q(y, PIDLAB_INPUT_FULL_SCALE), &out);
  *u = (double)out * PIDLAB_OUTPUT_FULL_SCALE / shim_two_n();
  return status;
}

int shim_set_manual(void *pid, double u) {
  return (int)pidlab_pid_set_manual((pidlab_pid *)pid, shim_q(u, PIDLAB_OUTPUT_FULL_SCALE));
}

void shim_set_auto(void *pid) { pidlab_pid_set_auto((pidlab_pid *)pid); }

int shim_set_gains(void *pid, double kp, double ki, double kd, double tf) {
  return (int)pidlab_pid_set_gains((pidlab_pid *)pid, kp, ki, kd, tf);
}

int shim_set_setpoint_weights(void *pid, double b, double c) {
  return (int)pidlab_pid_set_setpoint_weights((pidlab_pid *)pid, b, c);
}

int shim_set_sample_time(void *pid, double dt_s) {
  return (int)pidlab_pid_set_sample_time((pidlab_pid *)pid, dt_s);
}
