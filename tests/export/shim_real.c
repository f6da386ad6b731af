/* The generated floating-point controller behind a double interface, for
 * tests/export_test.cc, which loads it with dlopen (one shared object per
 * scalar, so that the double and float modules' names do not meet). */
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

void *shim_new(const shim_config *s) {
  pidlab_pid_config c;
  pidlab_pid *pid = (pidlab_pid *)malloc(sizeof(pidlab_pid));
  if (!pid) return NULL;
  c.kp = (pidlab_real)s->kp;
  c.ki = (pidlab_real)s->ki;
  c.kd = (pidlab_real)s->kd;
  c.tf = (pidlab_real)s->tf;
  c.setpoint_weight_b = (pidlab_real)s->b;
  c.setpoint_weight_c = (pidlab_real)s->c;
  c.setpoint_filter_s = (pidlab_real)s->setpoint_filter_s;
  c.dt_s = (pidlab_real)s->dt_s;
  c.has_output_min = s->has_output_min;
  c.output_min = (pidlab_real)s->output_min;
  c.has_output_max = s->has_output_max;
  c.output_max = (pidlab_real)s->output_max;
  c.anti_windup = (pidlab_anti_windup)s->anti_windup;
  c.back_calculation_gain = (pidlab_real)s->back_calculation_gain;
  c.integral = (pidlab_integral_rule)s->integral;
  if (pidlab_pid_init(pid, &c) != PIDLAB_PID_OK) {
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
  pidlab_real out = (pidlab_real)*u;
  int status = (int)pidlab_pid_step((pidlab_pid *)pid, (pidlab_real)r, (pidlab_real)y, &out);
  *u = (double)out;
  return status;
}

int shim_set_manual(void *pid, double u) {
  return (int)pidlab_pid_set_manual((pidlab_pid *)pid, (pidlab_real)u);
}

void shim_set_auto(void *pid) { pidlab_pid_set_auto((pidlab_pid *)pid); }

int shim_set_gains(void *pid, double kp, double ki, double kd, double tf) {
  return (int)pidlab_pid_set_gains((pidlab_pid *)pid, (pidlab_real)kp, (pidlab_real)ki, (pidlab_real)kd,
                                   (pidlab_real)tf);
}

int shim_set_setpoint_weights(void *pid, double b, double c) {
  return (int)pidlab_pid_set_setpoint_weights((pidlab_pid *)pid, (pidlab_real)b, (pidlab_real)c);
}

int shim_set_sample_time(void *pid, double dt_s) {
  return (int)pidlab_pid_set_sample_time((pidlab_pid *)pid, (pidlab_real)dt_s);
}
