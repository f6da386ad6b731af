// The generated C of the floating-point controller (double, float): the
// text of pidlab_pid.h and pidlab_pid.c with @NAME@ placeholders that
// export.cc fills. The step is DiscretePid::Step (pid.h) line for line.

#include "templates.h"

namespace pidlab::controller_export::internal {

const char* const kRealHeader = R"C(/* pidlab_pid.h: a discrete 2-DOF PID, exported by pidlab export.
 *
@COMMENT@ */
#ifndef PIDLAB_PID_H_
#define PIDLAB_PID_H_

#ifdef __cplusplus
extern "C" {
#endif

/* The controller's number type. Do not compile with -ffast-math (or
 * anything else that reorders floating-point operations): the outputs are
 * pidlab's only in this operation order. */
typedef @REAL@ pidlab_real;

typedef enum {
  PIDLAB_INTEGRAL_BACKWARD_EULER = 0, /* I += ki dt e_k */
  PIDLAB_INTEGRAL_FORWARD_EULER = 1,  /* I += ki dt e_{k-1} */
  PIDLAB_INTEGRAL_TRAPEZOIDAL = 2     /* I += ki dt/2 (e_k + e_{k-1}) */
} pidlab_integral_rule;

typedef enum {
  PIDLAB_ANTI_WINDUP_NONE = 0,
  /* while saturated, stop integrating if the error pushes further out */
  PIDLAB_ANTI_WINDUP_CLAMPING = 1,
  /* while saturated, I += back_calculation_gain dt (u_sat - u) */
  PIDLAB_ANTI_WINDUP_BACK_CALCULATION = 2
} pidlab_anti_windup;

typedef enum {
  PIDLAB_PID_OK = 0,            /* u computed, inside the limits */
  PIDLAB_PID_SATURATED = 1,     /* u computed and clipped to a limit */
  PIDLAB_PID_INVALID_INPUT = 2, /* r or y not finite: u and state untouched */
  PIDLAB_PID_INVALID_CONFIG = 3 /* a setter refused its values: nothing changed */
} pidlab_pid_status;

typedef struct {
  pidlab_real kp;   /* proportional gain */
  pidlab_real ki;   /* integral gain, 1/s */
  pidlab_real kd;   /* derivative gain, s */
  pidlab_real tf;   /* derivative filter time constant, s; 0 = unfiltered */
  pidlab_real setpoint_weight_b; /* b: setpoint weight of P, [0, 1] */
  pidlab_real setpoint_weight_c; /* c: setpoint weight of D, [0, 1]; 0 = on measurement */
  pidlab_real setpoint_filter_s; /* tr: setpoint filter r/(tr s + 1) before all terms, s, >= 0; 0 = none */
  pidlab_real dt_s; /* sample period, s, > 0: call pidlab_pid_step this often */
  int has_output_min; /* 0: no lower limit */
  pidlab_real output_min;
  int has_output_max; /* 0: no upper limit */
  pidlab_real output_max;
  pidlab_anti_windup anti_windup;
  pidlab_real back_calculation_gain; /* 1/s, > 0 */
  pidlab_integral_rule integral;
} pidlab_pid_config;

/* The controller: its configuration and its state. Treat as opaque. */
typedef struct {
  pidlab_pid_config config;
  pidlab_real half_dt;      /* dt / 2 */
  pidlab_real aw_gain_dt;   /* back_calculation_gain dt */
  pidlab_real integral;     /* I_{k-1} */
  pidlab_real integral_lo;  /* float: what rounding took from I (compensated sum); double: 0 */
  pidlab_real derivative;   /* D_{k-1} */
  pidlab_real prev_error;   /* e_{k-1} */
  pidlab_real prev_signal;  /* c r_{k-1} - y_{k-1} */
  pidlab_real prev_r;       /* r_{k-1}, for bumpless changes */
  pidlab_real prev_y;       /* y_{k-1} */
  pidlab_real filtered_r;   /* f_{k-1}, the setpoint filter's state (tr > 0) */
  int manual;               /* 1: the output follows manual_output */
  pidlab_real manual_output;
} pidlab_pid;

/* The configuration pidlab tuned (pidlab_pid.c). */
extern const pidlab_pid_config pidlab_pid_tuned;

/* Copies *config and resets; automatic mode. PIDLAB_PID_INVALID_CONFIG (and
 * *pid untouched) if a value is out of range. */
pidlab_pid_status pidlab_pid_init(pidlab_pid *pid, const pidlab_pid_config *config);

/* Back to rest (r = y = e = 0 before the next step), automatic mode. */
void pidlab_pid_reset(pidlab_pid *pid);

/* One sample: call it from your timer tick every dt_s with the setpoint r
 * and the measurement y; writes the control u. Never blocks, never fails
 * but for non-finite inputs. */
pidlab_pid_status pidlab_pid_step(pidlab_pid *pid, pidlab_real r, pidlab_real y, pidlab_real *u);

/* Manual mode: from now on pidlab_pid_step writes u_manual (clipped to the
 * limits) and the integrator tracks it, so that pidlab_pid_set_auto
 * continues from it without a bump. Call it again to move the output. */
pidlab_pid_status pidlab_pid_set_manual(pidlab_pid *pid, pidlab_real u_manual);
void pidlab_pid_set_auto(pidlab_pid *pid);

/* Run-time changes without a bump: the integrator absorbs the change of the
 * proportional term at the last sample, the derivative's memory is
 * rewritten for the new c; ki, kd, tf and dt_s act from the next sample on. */
pidlab_pid_status pidlab_pid_set_gains(pidlab_pid *pid, pidlab_real kp, pidlab_real ki, pidlab_real kd,
                                       pidlab_real tf);
pidlab_pid_status pidlab_pid_set_setpoint_weights(pidlab_pid *pid, pidlab_real b, pidlab_real c);
/* The setpoint filter's tr (s, >= 0; 0 = none): it acts from the next
 * sample, from the filter's present state (switched on: from the last
 * setpoint the terms saw, so without a bump). */
pidlab_pid_status pidlab_pid_set_setpoint_filter(pidlab_pid *pid, pidlab_real tr);
pidlab_pid_status pidlab_pid_set_sample_time(pidlab_pid *pid, pidlab_real dt_s);

#ifdef __cplusplus
}
#endif

#endif /* PIDLAB_PID_H_ */
)C";

const char* const kRealSource = R"C(/* pidlab_pid.c: a discrete 2-DOF PID, exported by pidlab export.
 * See pidlab_pid.h. C99, no library: not even <math.h>. */
#include "pidlab_pid.h"

const pidlab_pid_config pidlab_pid_tuned = {
@CONFIG@};

#define PIDLAB_ZERO ((pidlab_real)0)
#define PIDLAB_ONE ((pidlab_real)1)

/* Finite: x - x is 0 for every finite x, NaN for an infinity or a NaN. */
static int pidlab_is_finite(pidlab_real x) { return x - x == PIDLAB_ZERO; }

static int pidlab_in_unit(pidlab_real x) { return x >= PIDLAB_ZERO && x <= PIDLAB_ONE; }

/* kp, ki and kd share one sign: all >= 0 (direct acting) or all <= 0 (a
 * reverse-acting plant's PID). */
static int pidlab_gains_valid(pidlab_real kp, pidlab_real ki, pidlab_real kd, pidlab_real tf) {
  const int direct = kp >= PIDLAB_ZERO && ki >= PIDLAB_ZERO && kd >= PIDLAB_ZERO;
  const int reverse = kp <= PIDLAB_ZERO && ki <= PIDLAB_ZERO && kd <= PIDLAB_ZERO;
  return pidlab_is_finite(kp) && pidlab_is_finite(ki) && pidlab_is_finite(kd) && (direct || reverse) &&
         pidlab_is_finite(tf) && tf >= PIDLAB_ZERO;
}

static int pidlab_config_valid(const pidlab_pid_config *c) {
  if (!pidlab_gains_valid(c->kp, c->ki, c->kd, c->tf)) return 0;
  if (!pidlab_in_unit(c->setpoint_weight_b) || !pidlab_in_unit(c->setpoint_weight_c)) return 0;
  if (!pidlab_is_finite(c->setpoint_filter_s) || !(c->setpoint_filter_s >= PIDLAB_ZERO)) return 0;
  if (!pidlab_is_finite(c->dt_s) || !(c->dt_s > PIDLAB_ZERO)) return 0;
  if (c->has_output_min && !pidlab_is_finite(c->output_min)) return 0;
  if (c->has_output_max && !pidlab_is_finite(c->output_max)) return 0;
  if (c->has_output_min && c->has_output_max && !(c->output_min < c->output_max)) return 0;
  if (c->anti_windup == PIDLAB_ANTI_WINDUP_BACK_CALCULATION &&
      (!pidlab_is_finite(c->back_calculation_gain) || !(c->back_calculation_gain > PIDLAB_ZERO)))
    return 0;
  return c->integral == PIDLAB_INTEGRAL_BACKWARD_EULER || c->integral == PIDLAB_INTEGRAL_FORWARD_EULER ||
         c->integral == PIDLAB_INTEGRAL_TRAPEZOIDAL;
}

/* *sum += x. @ACCUMULATE_WHY@ */
static void pidlab_accumulate(pidlab_real *sum, pidlab_real *lo, pidlab_real x) {
@ACCUMULATE_BODY@}

static void pidlab_derive(pidlab_pid *pid) {
  pid->half_dt = pid->config.dt_s * (pidlab_real)0.5;
  pid->aw_gain_dt = pid->config.back_calculation_gain * pid->config.dt_s;
}

static pidlab_real pidlab_clip(const pidlab_pid_config *c, pidlab_real u) {
  if (c->has_output_max && u > c->output_max) u = c->output_max;
  if (c->has_output_min && u < c->output_min) u = c->output_min;
  return u;
}

/* The proportional term at the last sample: what a change of kp or b must
 * not change. */
static pidlab_real pidlab_last_p(const pidlab_pid *pid) {
  return pid->config.kp * (pid->config.setpoint_weight_b * pid->prev_r - pid->prev_y);
}

pidlab_pid_status pidlab_pid_init(pidlab_pid *pid, const pidlab_pid_config *config) {
  if (!pidlab_config_valid(config)) return PIDLAB_PID_INVALID_CONFIG;
  pid->config = *config;
  pidlab_derive(pid);
  pidlab_pid_reset(pid);
  return PIDLAB_PID_OK;
}

void pidlab_pid_reset(pidlab_pid *pid) {
  pid->integral = PIDLAB_ZERO;
  pid->integral_lo = PIDLAB_ZERO;
  pid->derivative = PIDLAB_ZERO;
  pid->prev_error = PIDLAB_ZERO;
  pid->prev_signal = PIDLAB_ZERO;
  pid->prev_r = PIDLAB_ZERO;
  pid->prev_y = PIDLAB_ZERO;
  pid->filtered_r = PIDLAB_ZERO;
  pid->manual = 0;
  pid->manual_output = PIDLAB_ZERO;
}

pidlab_pid_status pidlab_pid_step(pidlab_pid *pid, pidlab_real r, pidlab_real y, pidlab_real *u) {
  const pidlab_pid_config *c = &pid->config;
  pidlab_real e, p, integral, integral_lo, signal, tf, d, unsaturated, out;
  int saturated = 0;
  if (!pidlab_is_finite(r) || !pidlab_is_finite(y)) return PIDLAB_PID_INVALID_INPUT;
  if (c->setpoint_filter_s > PIDLAB_ZERO) {
    /* The setpoint filter: f_k = f_{k-1} + dt/(tr + dt) (r_k - f_{k-1}) in r's place. */
    pid->filtered_r += c->dt_s / (c->setpoint_filter_s + c->dt_s) * (r - pid->filtered_r);
    r = pid->filtered_r;
  }
  e = r - y;
  p = c->kp * (c->setpoint_weight_b * r - y);
  integral = pid->integral;
  integral_lo = pid->integral_lo;
  switch (c->integral) {
    case PIDLAB_INTEGRAL_FORWARD_EULER:
      pidlab_accumulate(&integral, &integral_lo, c->ki * c->dt_s * pid->prev_error);
      break;
    case PIDLAB_INTEGRAL_TRAPEZOIDAL:
      pidlab_accumulate(&integral, &integral_lo, c->ki * pid->half_dt * (e + pid->prev_error));
      break;
    case PIDLAB_INTEGRAL_BACKWARD_EULER:
    default:
      pidlab_accumulate(&integral, &integral_lo, c->ki * c->dt_s * e);
      break;
  }
  signal = c->setpoint_weight_c * r - y;
  tf = c->tf;
  /* @DERIVATIVE_WHY@ */
  d = @DERIVATIVE@;
  unsaturated = p + integral + d;
  out = unsaturated;
  if (pid->manual) {
    /* The integrator takes whatever makes p + I + D the manual output. */
    out = pid->manual_output;
    integral = out - p - d;
    integral_lo = PIDLAB_ZERO;
  } else {
    if (c->has_output_max && out > c->output_max) {
      out = c->output_max;
      saturated = 1;
    }
    if (c->has_output_min && out < c->output_min) {
      out = c->output_min;
      saturated = 1;
    }
    if (saturated) {
      if (c->anti_windup == PIDLAB_ANTI_WINDUP_CLAMPING) {
        /* Integrate only if the error pulls the output back inside. */
        /* (The integral moves u the way ki e does: against e where reverse acting.) */
        const pidlab_real pull = c->ki < PIDLAB_ZERO ? -e : e;
        const int pushes_further = (c->has_output_max && unsaturated > c->output_max && pull > PIDLAB_ZERO) ||
                                   (c->has_output_min && unsaturated < c->output_min && pull < PIDLAB_ZERO);
        if (pushes_further) {
          integral = pid->integral;
          integral_lo = pid->integral_lo;
        }
      } else if (c->anti_windup == PIDLAB_ANTI_WINDUP_BACK_CALCULATION) {
        pidlab_accumulate(&integral, &integral_lo, pid->aw_gain_dt * (out - unsaturated));
      }
    }
  }
  pid->integral = integral;
  pid->integral_lo = integral_lo;
  pid->derivative = d;
  pid->prev_error = e;
  pid->prev_signal = signal;
  pid->prev_r = r;
  pid->prev_y = y;
  *u = out;
  return saturated ? PIDLAB_PID_SATURATED : PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_manual(pidlab_pid *pid, pidlab_real u_manual) {
  if (!pidlab_is_finite(u_manual)) return PIDLAB_PID_INVALID_INPUT;
  pid->manual = 1;
  pid->manual_output = pidlab_clip(&pid->config, u_manual);
  /* Track at once, so that set_auto before the next step is bumpless too. */
  pid->integral = pid->manual_output - pidlab_last_p(pid) - pid->derivative;
  pid->integral_lo = PIDLAB_ZERO;
  return PIDLAB_PID_OK;
}

void pidlab_pid_set_auto(pidlab_pid *pid) { pid->manual = 0; }

pidlab_pid_status pidlab_pid_set_gains(pidlab_pid *pid, pidlab_real kp, pidlab_real ki, pidlab_real kd,
                                       pidlab_real tf) {
  pidlab_real p_before;
  if (!pidlab_gains_valid(kp, ki, kd, tf)) return PIDLAB_PID_INVALID_CONFIG;
  p_before = pidlab_last_p(pid);
  pid->config.kp = kp;
  pid->config.ki = ki;
  pid->config.kd = kd;
  pid->config.tf = tf;
  pidlab_accumulate(&pid->integral, &pid->integral_lo, p_before - pidlab_last_p(pid));
  return PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_setpoint_weights(pidlab_pid *pid, pidlab_real b, pidlab_real c) {
  pidlab_real p_before;
  if (!pidlab_in_unit(b) || !pidlab_in_unit(c)) return PIDLAB_PID_INVALID_CONFIG;
  p_before = pidlab_last_p(pid);
  pid->config.setpoint_weight_b = b;
  pid->config.setpoint_weight_c = c;
  pidlab_accumulate(&pid->integral, &pid->integral_lo, p_before - pidlab_last_p(pid));
  pid->prev_signal = c * pid->prev_r - pid->prev_y;
  return PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_setpoint_filter(pidlab_pid *pid, pidlab_real tr) {
  if (!pidlab_is_finite(tr) || !(tr >= PIDLAB_ZERO)) return PIDLAB_PID_INVALID_CONFIG;
  /* A filter switched on starts from the setpoint the terms saw last. */
  if (!(pid->config.setpoint_filter_s > PIDLAB_ZERO)) pid->filtered_r = pid->prev_r;
  pid->config.setpoint_filter_s = tr;
  return PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_sample_time(pidlab_pid *pid, pidlab_real dt_s) {
  if (!pidlab_is_finite(dt_s) || !(dt_s > PIDLAB_ZERO)) return PIDLAB_PID_INVALID_CONFIG;
  pid->config.dt_s = dt_s;
  pidlab_derive(pid);
  return PIDLAB_PID_OK;
}
)C";

}  // namespace pidlab::controller_export::internal
