// The generated C of the fixed-point controller (q31, q15): pidlab_pid.h and
// pidlab_pid.c with @NAME@ placeholders that fixed_point.cc fills. The step
// is DiscretePid::Step's structure in saturating integer arithmetic; the
// scalings and the range analysis come from fixed_point.cc.

#include "templates.h"

namespace pidlab::controller_export::internal {

const char* const kFixedHeader =
    R"C(/* pidlab_pid.h: a discrete 2-DOF PID in saturating fixed point, exported by pidlab export.
 *
@COMMENT@ */
#ifndef PIDLAB_PID_H_
#define PIDLAB_PID_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* r, y and u as @QNAME@ integers: r = q * PIDLAB_INPUT_FULL_SCALE / 2^@NIO@ and
 * u = q * PIDLAB_OUTPUT_FULL_SCALE / 2^@NIO@, in the loop's units. */
typedef @QTYPE@ pidlab_q;
#define PIDLAB_Q_BITS @NIO@
#define PIDLAB_INPUT_FULL_SCALE @X@
#define PIDLAB_OUTPUT_FULL_SCALE @U@
/* A constant in the loop's units as pidlab_q (for constants: the compiler
 * folds it; at run time it needs double arithmetic). */
#define PIDLAB_INPUT_Q(x) ((pidlab_q)((x) / PIDLAB_INPUT_FULL_SCALE * @TWO_NIO@ + ((x) < 0 ? -0.5 : 0.5)))
#define PIDLAB_OUTPUT_Q(x) ((pidlab_q)((x) / PIDLAB_OUTPUT_FULL_SCALE * @TWO_NIO@ + ((x) < 0 ? -0.5 : 0.5)))

typedef enum {
  PIDLAB_INTEGRAL_BACKWARD_EULER = 0,
  PIDLAB_INTEGRAL_FORWARD_EULER = 1,
  PIDLAB_INTEGRAL_TRAPEZOIDAL = 2
} pidlab_integral_rule;

typedef enum {
  PIDLAB_ANTI_WINDUP_NONE = 0,
  PIDLAB_ANTI_WINDUP_CLAMPING = 1,
  PIDLAB_ANTI_WINDUP_BACK_CALCULATION = 2
} pidlab_anti_windup;

typedef enum {
  PIDLAB_PID_OK = 0,
  PIDLAB_PID_SATURATED = 1,
  PIDLAB_PID_INVALID_INPUT = 2, /* not used by the fixed-point step: every integer is an input */
  PIDLAB_PID_INVALID_CONFIG = 3 /* refused: out of range, or beyond the range analysis */
} pidlab_pid_status;

/* The configuration in the loop's units (double: read once by init and the
 * setters, which turn it into integer coefficients; the step uses no
 * floating point). */
typedef struct {
  double kp, ki, kd, tf, setpoint_weight_b, setpoint_weight_c;
  double setpoint_filter_s; /* tr: setpoint filter r/(tr s + 1) before all terms, s, >= 0; 0 = none */
  double dt_s;
  double output_min, output_max; /* finite, inside +-PIDLAB_OUTPUT_FULL_SCALE */
  pidlab_anti_windup anti_windup;
  double back_calculation_gain;
  pidlab_integral_rule integral;
} pidlab_pid_config;

/* value = m 2^-s */
typedef struct {
  uint64_t m;
  int32_t s;
} pidlab_coef;

typedef struct {
  pidlab_pid_config config;
  pidlab_coef kp, ki_dt, ki_half_dt, kd_k, pole_g, aw, b, c, filter_g;
  int64_t output_min, output_max; /* in accumulator units */
  int64_t integral, derivative;   /* accumulator units */
  int64_t prev_error, prev_r, prev_y; /* input units (2^-31 of the input full scale) */
  int filtering;                      /* 1: the setpoint filter runs (tr > 0) */
  int64_t filtered_r;                 /* its state, in 2^-20 input units */
  int manual;
  int64_t manual_output;
  /* Gains all <= 0 (a reverse-acting plant's): run as the PID of |gains| on
   * -r and -y, the same u; the inputs kept above are the negated ones. */
  int reverse;
} pidlab_pid;

extern const pidlab_pid_config pidlab_pid_tuned;

pidlab_pid_status pidlab_pid_init(pidlab_pid *pid, const pidlab_pid_config *config);
void pidlab_pid_reset(pidlab_pid *pid);
/* One sample from your timer tick. r and y outside the declared input range
 * are clipped to it; u never leaves the output limits, and nothing wraps. */
pidlab_pid_status pidlab_pid_step(pidlab_pid *pid, pidlab_q r, pidlab_q y, pidlab_q *u);
pidlab_pid_status pidlab_pid_set_manual(pidlab_pid *pid, pidlab_q u_manual);
void pidlab_pid_set_auto(pidlab_pid *pid);
/* Run-time changes without a bump; refused (PIDLAB_PID_INVALID_CONFIG) if
 * the new values' worst case exceeds the range analysis above. */
pidlab_pid_status pidlab_pid_set_gains(pidlab_pid *pid, double kp, double ki, double kd, double tf);
pidlab_pid_status pidlab_pid_set_setpoint_weights(pidlab_pid *pid, double b, double c);
/* The setpoint filter's tr (s, >= 0; 0 = none); switched on, it starts from
 * the last setpoint the terms saw. */
pidlab_pid_status pidlab_pid_set_setpoint_filter(pidlab_pid *pid, double tr);
pidlab_pid_status pidlab_pid_set_sample_time(pidlab_pid *pid, double dt_s);

#ifdef __cplusplus
}
#endif

#endif /* PIDLAB_PID_H_ */
)C";

const char* const kFixedSource =
    R"C(/* pidlab_pid.c: a discrete 2-DOF PID in saturating fixed point, exported by
 * pidlab export. See pidlab_pid.h for the scalings and the range analysis. */
#include "pidlab_pid.h"

const pidlab_pid_config pidlab_pid_tuned = {
@CONFIG@};

/* Inputs inside the declared range, in input units (2^-31 of the input
 * full scale). */
#define PIDLAB_INPUT_LO ((int64_t)@INPUT_LO@)
#define PIDLAB_INPUT_HI ((int64_t)@INPUT_HI@)
/* Accumulator units: 2^-(31 + G) of the output full scale, G = @GUARD@. */
#define PIDLAB_ACC_PER_INPUT_REAL @ACC_PER_INPUT@ /* (X / U) 2^G: input units -> accumulator units */
#define PIDLAB_ACC_ONE_REAL @ACC_ONE@ /* 2^(31 + G) / U: one output unit in accumulator units */
#define PIDLAB_IO_SHIFT @IO_SHIFT@ /* accumulator -> pidlab_q: 2^(G + 31 - @NIO@) */
#define PIDLAB_INPUT_SHIFT_MUL ((int64_t)@INPUT_MUL@) /* pidlab_q -> input units */
/* The range analysis' bound on |I| and on the worst case a configuration may
 * have (accumulator units, and in the loop's output units). */
#define PIDLAB_INTEGRAL_MAX ((int64_t)@INTEGRAL_MAX@)
#define PIDLAB_WORST_CASE_MAX_REAL @WORST_MAX@
#define PIDLAB_INPUT_RANGE_REAL @INPUT_RANGE@ /* max(|lo|, |hi|) */
#define PIDLAB_INPUT_SPAN_REAL @INPUT_SPAN@ /* hi - lo */

static int64_t pidlab_sat_add(int64_t a, int64_t b) {
  if (b > 0 && a > INT64_MAX - b) return INT64_MAX;
  if (b < 0 && a < INT64_MIN - b) return INT64_MIN;
  return a + b;
}

static int64_t pidlab_sat_sub(int64_t a, int64_t b) {
  if (b == INT64_MIN) return a >= 0 ? INT64_MAX : a - b;
  return pidlab_sat_add(a, -b);
}

static int64_t pidlab_clamp(int64_t x, int64_t lo, int64_t hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* One input unit in the setpoint filter's state units. */
#define PIDLAB_FILTER_ONE ((int64_t)1 << 20)

/* a m 2^-s, rounded to nearest, saturated: the 128-bit product from four
 * 32x32 -> 64-bit products, in sign and magnitude, so that no negative
 * number is shifted. */
static int64_t pidlab_mul(int64_t a, pidlab_coef c) {
  const int negative = a < 0;
  const uint64_t mag = negative ? (uint64_t)0 - (uint64_t)a : (uint64_t)a;
  const uint64_t a0 = mag & 0xffffffffu, a1 = mag >> 32, m0 = c.m & 0xffffffffu, m1 = c.m >> 32;
  const uint64_t p00 = a0 * m0, p01 = a0 * m1, p10 = a1 * m0, p11 = a1 * m1;
  const uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
  const uint64_t lo = (mid << 32) | (p00 & 0xffffffffu);
  const uint64_t hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
  const unsigned s = (unsigned)c.s;
  uint64_t result, round;
  if (s >= 128) {
    result = 0;
    round = 0;
  } else if (s > 64) {
    result = hi >> (s - 64);
    round = (hi >> (s - 65)) & 1u;
  } else if (s == 64) {
    result = hi;
    round = lo >> 63;
  } else if (s == 0) {
    result = hi ? UINT64_MAX : lo;
    round = 0;
  } else {
    result = (hi >> s) ? UINT64_MAX : (hi << (64 - s)) | (lo >> s);
    round = (lo >> (s - 1)) & 1u;
  }
  if (result < UINT64_MAX) result += round;
  if (result > (uint64_t)INT64_MAX) result = (uint64_t)INT64_MAX;
  return negative ? -(int64_t)result : (int64_t)result;
}

/* v >= 0 as m 2^-s with m in [2^63, 2^64): a double in that range is an
 * integer, so m 2^-s is v exactly (v = 0: m = 0). 0 if v >= 2^64 or is not
 * finite. */
static int pidlab_encode(double v, pidlab_coef *c) {
  int32_t s = 0;
  if (!(v >= 0.0) || !(v < 18446744073709551616.0)) return 0;
  c->m = 0;
  c->s = 127;
  if (v == 0.0) return 1;
  while (v < 9223372036854775808.0 && s < 127) {
    v *= 2.0;
    ++s;
  }
  c->m = (uint64_t)v;
  c->s = s;
  return 1;
}

static int64_t pidlab_round_to_int64(double v) { return (int64_t)(v < 0.0 ? v - 0.5 : v + 0.5); }

static int pidlab_finite(double x) { return x - x == 0.0; }

/* The worst case of |p| + |D| + |u| of a configuration, in the loop's output
 * units: what the range analysis bounds. */
static double pidlab_abs(double x) { return x < 0.0 ? -x : x; }

static double pidlab_worst_case(const pidlab_pid_config *c) {
  const double limit = c->output_max > -c->output_min ? c->output_max : -c->output_min;
  return pidlab_abs(c->kp) * (c->setpoint_weight_b + 1.0) * PIDLAB_INPUT_RANGE_REAL +
         pidlab_abs(c->kd) * (1.0 + c->setpoint_weight_c) * PIDLAB_INPUT_SPAN_REAL / c->dt_s + limit;
}

/* Gains all <= 0 with one < 0: a reverse-acting loop. */
static int pidlab_reverse(const pidlab_pid_config *c) { return c->kp < 0.0 || c->ki < 0.0 || c->kd < 0.0; }

static int pidlab_unit(double x) { return x >= 0.0 && x <= 1.0; }

static int pidlab_config_valid(const pidlab_pid_config *c) {
  /* kp, ki, kd share one sign: all >= 0, or all <= 0 (reverse acting) */
  if (!(pidlab_finite(c->kp) && pidlab_finite(c->ki) && pidlab_finite(c->kd) && pidlab_finite(c->tf) && c->tf >= 0.0))
    return 0;
  if (!((c->kp >= 0.0 && c->ki >= 0.0 && c->kd >= 0.0) || (c->kp <= 0.0 && c->ki <= 0.0 && c->kd <= 0.0))) return 0;
  if (!pidlab_unit(c->setpoint_weight_b) || !pidlab_unit(c->setpoint_weight_c) || !pidlab_finite(c->dt_s) || !(c->dt_s > 0.0)) return 0;
  if (!pidlab_finite(c->setpoint_filter_s) || !(c->setpoint_filter_s >= 0.0)) return 0;
  if (!pidlab_finite(c->output_min) || !pidlab_finite(c->output_max) || !(c->output_min < c->output_max)) return 0;
  if (c->output_max > PIDLAB_OUTPUT_FULL_SCALE || c->output_min < -PIDLAB_OUTPUT_FULL_SCALE) return 0;
  if (!pidlab_finite(c->back_calculation_gain) || !(c->back_calculation_gain > 0.0)) return 0;
  if (c->integral != PIDLAB_INTEGRAL_BACKWARD_EULER && c->integral != PIDLAB_INTEGRAL_FORWARD_EULER &&
      c->integral != PIDLAB_INTEGRAL_TRAPEZOIDAL)
    return 0;
  return pidlab_worst_case(c) <= PIDLAB_WORST_CASE_MAX_REAL;
}

/* The integer coefficients of a valid configuration; 0 if one does not fit. */
static int pidlab_coefficients(const pidlab_pid_config *c, pidlab_pid *pid) {
  const double a = PIDLAB_ACC_PER_INPUT_REAL;
  const double kp = pidlab_abs(c->kp), ki = pidlab_abs(c->ki), kd = pidlab_abs(c->kd);
  return pidlab_encode(kp * a, &pid->kp) && pidlab_encode(ki * c->dt_s * a, &pid->ki_dt) &&
         pidlab_encode(ki * (c->dt_s * 0.5) * a, &pid->ki_half_dt) &&
         pidlab_encode(kd / (c->tf + c->dt_s) * a, &pid->kd_k) &&
         pidlab_encode(c->dt_s / (c->tf + c->dt_s), &pid->pole_g) &&
         pidlab_encode(c->back_calculation_gain * c->dt_s, &pid->aw) && pidlab_encode(c->setpoint_weight_b, &pid->b) &&
         pidlab_encode(c->setpoint_weight_c, &pid->c) &&
         pidlab_encode(c->setpoint_filter_s > 0.0 ? c->dt_s / (c->setpoint_filter_s + c->dt_s) : 1.0, &pid->filter_g);
}

/* A configuration in place of the current one, or nothing changed. */
static int pidlab_apply(pidlab_pid *pid, const pidlab_pid_config *config) {
  pidlab_pid next = *pid;
  if (!pidlab_config_valid(config)) return 0;
  next.config = *config;
  if (!pidlab_coefficients(config, &next)) return 0;
  if (pidlab_reverse(config) != next.reverse) {
    /* The inputs kept change sign with the direction; the integral and the
     * derivative are in u's units, the same either way. */
    next.prev_error = -next.prev_error;
    next.prev_r = -next.prev_r;
    next.prev_y = -next.prev_y;
    next.filtered_r = -next.filtered_r;
    next.reverse = pidlab_reverse(config);
  }
  /* A setpoint filter switched on starts from the setpoint the terms saw last. */
  if (!next.filtering && config->setpoint_filter_s > 0.0) next.filtered_r = next.prev_r * PIDLAB_FILTER_ONE;
  next.filtering = config->setpoint_filter_s > 0.0;
  next.output_min = pidlab_round_to_int64(config->output_min * PIDLAB_ACC_ONE_REAL);
  next.output_max = pidlab_round_to_int64(config->output_max * PIDLAB_ACC_ONE_REAL);
  *pid = next;
  return 1;
}

static int64_t pidlab_last_p(const pidlab_pid *pid) {
  return pidlab_mul(pidlab_sat_sub(pidlab_mul(pid->prev_r, pid->b), pid->prev_y), pid->kp);
}

static int64_t pidlab_limit_integral(int64_t i) { return pidlab_clamp(i, -PIDLAB_INTEGRAL_MAX, PIDLAB_INTEGRAL_MAX); }

pidlab_pid_status pidlab_pid_init(pidlab_pid *pid, const pidlab_pid_config *config) {
  pidlab_pid next;
  pidlab_pid_reset(&next);
  next.reverse = 0;
  next.filtering = 0;
  if (!pidlab_apply(&next, config)) return PIDLAB_PID_INVALID_CONFIG;
  *pid = next;
  return PIDLAB_PID_OK;
}

void pidlab_pid_reset(pidlab_pid *pid) {
  pid->integral = 0;
  pid->derivative = 0;
  pid->prev_error = 0;
  pid->prev_r = 0;
  pid->prev_y = 0;
  pid->filtered_r = 0;
  pid->manual = 0;
  pid->manual_output = 0;
}

static int64_t pidlab_input(pidlab_q q) {
  return pidlab_clamp((int64_t)q * PIDLAB_INPUT_SHIFT_MUL, PIDLAB_INPUT_LO, PIDLAB_INPUT_HI);
}

static pidlab_q pidlab_output(int64_t acc) {
  const int negative = acc < 0;
  const uint64_t mag = negative ? (uint64_t)0 - (uint64_t)acc : (uint64_t)acc;
  uint64_t q = (mag >> PIDLAB_IO_SHIFT) + ((mag >> (PIDLAB_IO_SHIFT - 1)) & 1u);
  int64_t v;
  if (q > ((uint64_t)1 << PIDLAB_Q_BITS)) q = (uint64_t)1 << PIDLAB_Q_BITS;
  v = negative ? -(int64_t)q : (int64_t)q;
  if (v > (int64_t)((((uint64_t)1) << PIDLAB_Q_BITS) - 1)) v = (int64_t)((((uint64_t)1) << PIDLAB_Q_BITS) - 1);
  return (pidlab_q)v;
}

pidlab_pid_status pidlab_pid_step(pidlab_pid *pid, pidlab_q r_q, pidlab_q y_q, pidlab_q *u) {
  const pidlab_pid_config *c = &pid->config;
  int64_t r = pid->reverse ? -pidlab_input(r_q) : pidlab_input(r_q);
  const int64_t y = pid->reverse ? -pidlab_input(y_q) : pidlab_input(y_q);
  int64_t e;
  if (pid->filtering) {
    /* The setpoint filter f += dt/(tr + dt) (r - f), in r's place; f is kept
     * 20 bits finer than the inputs, so that its rounding stays below one
     * input unit. */
    pid->filtered_r += pidlab_mul(r * PIDLAB_FILTER_ONE - pid->filtered_r, pid->filter_g);
    r = (pid->filtered_r + (pid->filtered_r < 0 ? -PIDLAB_FILTER_ONE / 2 : PIDLAB_FILTER_ONE / 2)) / PIDLAB_FILTER_ONE;
  }
  e = r - y;
  const int64_t p = pidlab_mul(pidlab_mul(r, pid->b) - y, pid->kp);
  int64_t integral = pid->integral, d, unsaturated, out, delta_signal;
  int saturated = 0;
  switch (c->integral) {
    case PIDLAB_INTEGRAL_FORWARD_EULER:
      integral = pidlab_sat_add(integral, pidlab_mul(pid->prev_error, pid->ki_dt));
      break;
    case PIDLAB_INTEGRAL_TRAPEZOIDAL:
      integral = pidlab_sat_add(integral, pidlab_mul(e + pid->prev_error, pid->ki_half_dt));
      break;
    case PIDLAB_INTEGRAL_BACKWARD_EULER:
    default:
      integral = pidlab_sat_add(integral, pidlab_mul(e, pid->ki_dt));
      break;
  }
  integral = pidlab_limit_integral(integral);
  /* D + (kd (s_k - s_{k-1}) - dt D) / (tf + dt): DiscretePid's
   * tf/(tf+dt) D + kd (s_k - s_{k-1}) / (tf + dt) without rounding the pole
   * near 1; s_k - s_{k-1} = c (r_k - r_{k-1}) - (y_k - y_{k-1}) exactly. */
  delta_signal = pidlab_mul(r - pid->prev_r, pid->c) - (y - pid->prev_y);
  d = pidlab_sat_add(pidlab_sat_sub(pid->derivative, pidlab_mul(pid->derivative, pid->pole_g)),
                     pidlab_mul(delta_signal, pid->kd_k));
  unsaturated = pidlab_sat_add(pidlab_sat_add(p, integral), d);
  out = unsaturated;
  if (pid->manual) {
    out = pid->manual_output;
    integral = pidlab_limit_integral(pidlab_sat_sub(pidlab_sat_sub(out, p), d));
  } else {
    if (out > pid->output_max) {
      out = pid->output_max;
      saturated = 1;
    }
    if (out < pid->output_min) {
      out = pid->output_min;
      saturated = 1;
    }
    if (saturated) {
      if (c->anti_windup == PIDLAB_ANTI_WINDUP_CLAMPING) {
        if ((unsaturated > pid->output_max && e > 0) || (unsaturated < pid->output_min && e < 0))
          integral = pid->integral;
      } else if (c->anti_windup == PIDLAB_ANTI_WINDUP_BACK_CALCULATION) {
        integral = pidlab_limit_integral(pidlab_sat_add(integral, pidlab_mul(pidlab_sat_sub(out, unsaturated), pid->aw)));
      }
    }
  }
  pid->integral = integral;
  pid->derivative = d;
  pid->prev_error = e;
  pid->prev_r = r;
  pid->prev_y = y;
  *u = pidlab_output(out);
  return saturated ? PIDLAB_PID_SATURATED : PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_manual(pidlab_pid *pid, pidlab_q u_manual) {
  const int64_t u = pidlab_clamp((int64_t)u_manual * ((int64_t)1 << PIDLAB_IO_SHIFT), pid->output_min, pid->output_max);
  pid->manual = 1;
  pid->manual_output = u;
  pid->integral = pidlab_limit_integral(pidlab_sat_sub(pidlab_sat_sub(u, pidlab_last_p(pid)), pid->derivative));
  return PIDLAB_PID_OK;
}

void pidlab_pid_set_auto(pidlab_pid *pid) { pid->manual = 0; }

/* The new configuration, the integrator moved by the change of the last
 * proportional term (no bump). */
static pidlab_pid_status pidlab_change(pidlab_pid *pid, const pidlab_pid_config *config) {
  const int64_t p_before = pidlab_last_p(pid);
  if (!pidlab_apply(pid, config)) return PIDLAB_PID_INVALID_CONFIG;
  pid->integral = pidlab_limit_integral(pidlab_sat_add(pid->integral, pidlab_sat_sub(p_before, pidlab_last_p(pid))));
  return PIDLAB_PID_OK;
}

pidlab_pid_status pidlab_pid_set_gains(pidlab_pid *pid, double kp, double ki, double kd, double tf) {
  pidlab_pid_config config = pid->config;
  config.kp = kp;
  config.ki = ki;
  config.kd = kd;
  config.tf = tf;
  return pidlab_change(pid, &config);
}

pidlab_pid_status pidlab_pid_set_setpoint_weights(pidlab_pid *pid, double b, double c) {
  pidlab_pid_config config = pid->config;
  config.setpoint_weight_b = b;
  config.setpoint_weight_c = c;
  return pidlab_change(pid, &config);
}

pidlab_pid_status pidlab_pid_set_setpoint_filter(pidlab_pid *pid, double tr) {
  pidlab_pid_config config = pid->config;
  config.setpoint_filter_s = tr;
  return pidlab_change(pid, &config);
}

pidlab_pid_status pidlab_pid_set_sample_time(pidlab_pid *pid, double dt_s) {
  pidlab_pid_config config = pid->config;
  config.dt_s = dt_s;
  return pidlab_change(pid, &config);
}
)C";

}  // namespace pidlab::controller_export::internal
