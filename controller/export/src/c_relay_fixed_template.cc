// The generated C of the relay autotune in fixed point (`pidlab export
// --autotune --scalar q31|q15`): pidlab_relay.h and pidlab_relay.c over the
// fixed-point PID. It is controller/relay.h's RelayTuner with q_bits set
// (relay.cc, "Fixed point") line for line, in the same operation order: y on
// the input's grid, u on the output's, time in steps, every switch an
// integer comparison (integration.autotune.firmware_fixed).

#include "templates.h"

namespace pidlab::controller_export::internal {

const char* const kRelayFixedHeader =
    R"C(/* pidlab_relay.h: the relay autotune in fixed point, exported by pidlab export --autotune.
 *
 * The state machine pidlab-controller runs in a relay episode
 * (docs/autotune.md), over the exported fixed-point PID as the loop in
 * place, one call per sample period (the PID's dt_s):
 *   hold   the previous PID (or u0 in open loop, the gains all 0) for
 *          hold_s; its second half gives the operating point (mean u, mean
 *          y) and the noise sigma (second differences of y);
 *   relay  u0 + d_high while y - y0 < -eps, u0 - d_low while y - y0 > eps,
 *          d_high = amplitude + bias and d_low = amplitude - bias cut to the
 *          output range, eps = hysteresis + noise_multiple sigma;
 *   end    done (the last settled cycles agree), or aborted (no room for the
 *          relay, |y - y0| beyond y_limit, no convergence within
 *          timeout_periods periods, a load change without a PID or after
 *          max_restarts restarts); a load change restarts from the hold.
 *   after  the previous PID again, or u0.
 * r, y and u are pidlab_q (pidlab_pid.h's scalings); u0, y0, eps and the
 * relay's levels are integers on the same grids, and every switch is an
 * integer comparison. Time counts steps. Double arithmetic runs once per
 * hold (the means, sigma: <math.h> sqrt and floor) and once per cycle (the
 * cycle in seconds and the convergence tests), as in pidlab autotune's
 * RelayTuner, never in the other steps. pidlab autotune --scalar q31|q15
 * reproduces every switch, and the input within 3 LSB (q31) or 2 LSB (q15):
 * the previous PID's rounding (docs/export.md), through the mean u0. */
#ifndef PIDLAB_RELAY_H_
#define PIDLAB_RELAY_H_

#include <stdint.h>

#include "pidlab_pid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The most cycles kept: settled_cycles (at most 100) and the approach. */
#define PIDLAB_RELAY_MAX_CYCLES 101
/* Under noise (3 sigma above 1 % of a cycle's amplitude) at least this
 * many settled cycles. */
#define PIDLAB_RELAY_NOISY_SETTLED_CYCLES 10
/* A relay the noise switches (pidlab/controller/relay.h, kQuietShift): under
 * noise, this many cycles in a row of at least PIDLAB_RELAY_QUIET_MIN_STEPS
 * steps whose smoothed e (f += (e - f) / 16) keeps a half range under 0.6
 * of the hysteresis end the relay (PIDLAB_RELAY_END_NOISE). */
#define PIDLAB_RELAY_QUIET_CYCLES 2
#define PIDLAB_RELAY_QUIET_MIN_STEPS 128

typedef enum {
  PIDLAB_RELAY_HOLD = 0,
  PIDLAB_RELAY_RELAY = 1,
  PIDLAB_RELAY_DONE = 2,
  PIDLAB_RELAY_ABORTED = 3
} pidlab_relay_phase;

typedef enum {
  PIDLAB_RELAY_END_NONE = 0,
  PIDLAB_RELAY_END_CONVERGED = 1,
  PIDLAB_RELAY_END_NO_ROOM = 2,          /* no room for the relay around u0 in the output range */
  PIDLAB_RELAY_END_Y_LIMIT = 3,          /* |y - y0| beyond y_limit */
  PIDLAB_RELAY_END_TIMEOUT = 4,          /* no convergence within timeout_periods periods */
  PIDLAB_RELAY_END_LOAD_CHANGE = 5,      /* a load change with no PID to hold the process */
  PIDLAB_RELAY_END_TOO_MANY_RESTARTS = 6, /* a load change after max_restarts restarts */
  PIDLAB_RELAY_END_NOISE = 7              /* the noise switches the relay: a larger amplitude is needed */
} pidlab_relay_end;

/* In the loop's units (read once by init). */
typedef struct {
  double hold_s;         /* >= 0 */
  double u0;             /* the open-loop hold's input */
  double amplitude;      /* d > 0 */
  double bias;           /* |b| < d */
  double hysteresis;     /* >= 0 */
  double noise_multiple; /* >= 0 */
  double y_limit;        /* > 0 (INFINITY: none) */
  int settled_cycles;    /* in [2, 100] */
  double tolerance;      /* in (0, 1) */
  double timeout_periods; /* > settled_cycles + 1 */
  int max_restarts;      /* in [0, 100] */
} pidlab_relay_config;

/* A cycle in seconds and the loop's units (computed once, at its end). */
typedef struct {
  double start_s, t_on_s, t_off_s, e_max, e_min, integral_e, integral_on_e;
} pidlab_relay_cycle;

/* Treat as opaque; read it with the functions below. */
typedef struct {
  pidlab_relay_config config;
  pidlab_pid *pid; /* the previous loop */
  int has_pid;
  double dt_s, qy, qu;
  int64_t hold_steps, out_min, out_max, hyst, dh, dl, y_limit, u0_config;
  pidlab_relay_phase phase;
  int first;
  int64_t k, hold_start, sum_u, sum_y, sum_d, y_prev, y_prev2;
  uint64_t sum_d2;
  long n_u, n_d, n_prev;
  double sigma;
  int64_t u0, y0, eps, d_high, d_low, relay_start;
  int high;
  int64_t e_prev, k_high, k_low, e_max, e_min, integral, integral_on, timeout;
  int64_t f, f_max, f_min; /* e smoothed (f += (e - f) / 16, rounded), its extremes in the cycle */
  long cycle_steps;
  int quiet; /* cycles in a row whose smoothed e stayed inside the hysteresis */
  pidlab_relay_cycle cycles[PIDLAB_RELAY_MAX_CYCLES]; /* a ring: the last ones */
  long n_cycles;                                      /* since the relay's last start */
  long n_changes;
  double last_change;
  int restarts;
  int64_t end_step;
  pidlab_relay_end end;
  double load_change_s; /* the last load change's cycle start, s; -1: none */
} pidlab_relay;

/* `pid` is the previous loop, initialised (pidlab_pid_init) and not stepped
 * elsewhere while the relay runs; its output limits are the relay's range
 * and its dt_s the step's period. 0 on success, -1 if a value is out of
 * range (nothing changed). */
int pidlab_relay_init(pidlab_relay *relay, const pidlab_relay_config *config, pidlab_pid *pid);

/* One sample (every dt_s) with setpoint r and measurement y: the input to
 * apply until the next one. */
pidlab_q pidlab_relay_step(pidlab_relay *relay, pidlab_q r, pidlab_q y);

pidlab_relay_phase pidlab_relay_get_phase(const pidlab_relay *relay);
pidlab_relay_end pidlab_relay_get_end(const pidlab_relay *relay);
/* The cycles since the relay's last start, and cycle i of them (0 the
 * approach; only the last PIDLAB_RELAY_MAX_CYCLES are kept). */
long pidlab_relay_cycle_count(const pidlab_relay *relay);
const pidlab_relay_cycle *pidlab_relay_cycle_at(const pidlab_relay *relay, long i);

#ifdef __cplusplus
}
#endif

#endif /* PIDLAB_RELAY_H_ */
)C";

const char* const kRelayFixedSource =
    R"C(/* pidlab_relay.c: the relay autotune in fixed point, exported by pidlab
 * export --autotune. See pidlab_relay.h. C99 and <math.h>. */
#include "pidlab_relay.h"

#include <math.h>

#define PIDLAB_RELAY_TOP ((double)(1LL << PIDLAB_Q_BITS))
/* The second differences in units of 2^SHIFT grid steps: their squares' sum
 * fits 64 bits. */
#define PIDLAB_RELAY_SHIFT (PIDLAB_Q_BITS > 23 ? PIDLAB_Q_BITS - 23 : 0)

/* floor(x + 0.5) clamped to [lo, hi]. */
static int64_t round_clamp(double x, double lo, double hi) {
  const double r = floor(x + 0.5);
  return (int64_t)(r < lo ? lo : (r > hi ? hi : r));
}
static int64_t q_out(double v) {
  return round_clamp(ldexp(v / PIDLAB_OUTPUT_FULL_SCALE, PIDLAB_Q_BITS), -PIDLAB_RELAY_TOP,
                     PIDLAB_RELAY_TOP - 1.0);
}
static int64_t shift_round(int64_t d) {
#if PIDLAB_RELAY_SHIFT == 0
  return d;
#else
  const int64_t half = (int64_t)1 << (PIDLAB_RELAY_SHIFT - 1);
  return d >= 0 ? (d + half) >> PIDLAB_RELAY_SHIFT : -((-d + half) >> PIDLAB_RELAY_SHIFT);
#endif
}
/* d / 16 rounded half away from zero. */
static int64_t quiet_shift(int64_t d) { return d >= 0 ? (d + 8) >> 4 : -((-d + 8) >> 4); }
static int64_t max64(int64_t a, int64_t b) { return a < b ? b : a; }
static int64_t min64(int64_t a, int64_t b) { return b < a ? b : a; }
static double period(const pidlab_relay_cycle *c) { return c->t_on_s + c->t_off_s; }
static double amplitude(const pidlab_relay_cycle *c) { return 0.5 * (c->e_max - c->e_min); }
static const pidlab_relay_cycle *back(const pidlab_relay *s, long i) {
  return &s->cycles[(s->n_cycles - 1 - i) % PIDLAB_RELAY_MAX_CYCLES];
}

int pidlab_relay_init(pidlab_relay *s, const pidlab_relay_config *c, pidlab_pid *pid) {
  double ylim;
  if (!(c->hold_s >= 0 && isfinite(c->hold_s)) || !isfinite(c->u0) ||
      !(c->amplitude > 0 && isfinite(c->amplitude)) || !(fabs(c->bias) < c->amplitude) ||
      !(c->hysteresis >= 0 && isfinite(c->hysteresis)) ||
      !(c->noise_multiple >= 0 && isfinite(c->noise_multiple)) || !(c->y_limit > 0) ||
      c->settled_cycles < 2 || c->settled_cycles > 100 || !(c->tolerance > 0 && c->tolerance < 1) ||
      !(c->timeout_periods > c->settled_cycles + 1) || !isfinite(c->timeout_periods) || c->max_restarts < 0 ||
      c->max_restarts > 100 || pid == 0)
    return -1;
  s->config = *c;
  s->pid = pid;
  s->has_pid = pid->config.kp != 0.0 || pid->config.ki != 0.0 || pid->config.kd != 0.0;
  s->dt_s = pid->config.dt_s;
  s->qy = ldexp(PIDLAB_INPUT_FULL_SCALE, -PIDLAB_Q_BITS);
  s->qu = ldexp(PIDLAB_OUTPUT_FULL_SCALE, -PIDLAB_Q_BITS);
  s->hold_steps = round_clamp(c->hold_s / s->dt_s, 0.0, 4e18);
  s->out_min = q_out(pid->config.output_min);
  s->out_max = q_out(pid->config.output_max);
  s->hyst = round_clamp(ldexp(c->hysteresis / PIDLAB_INPUT_FULL_SCALE, PIDLAB_Q_BITS), 0.0, PIDLAB_RELAY_TOP);
  s->dh = round_clamp(ldexp((c->amplitude + c->bias) / PIDLAB_OUTPUT_FULL_SCALE, PIDLAB_Q_BITS), 0.0,
                      2.0 * PIDLAB_RELAY_TOP);
  s->dl = round_clamp(ldexp((c->amplitude - c->bias) / PIDLAB_OUTPUT_FULL_SCALE, PIDLAB_Q_BITS), 0.0,
                      2.0 * PIDLAB_RELAY_TOP);
  ylim = ldexp(c->y_limit / PIDLAB_INPUT_FULL_SCALE, PIDLAB_Q_BITS);
  s->y_limit = (int64_t)floor(4611686018427387904.0 < ylim ? 4611686018427387904.0 : ylim);
  s->u0_config = min64(max64(q_out(c->u0), s->out_min), s->out_max);
  s->phase = PIDLAB_RELAY_HOLD;
  s->first = 1;
  s->k = s->hold_start = s->sum_u = s->sum_y = s->sum_d = s->y_prev = s->y_prev2 = 0;
  s->sum_d2 = 0;
  s->n_u = s->n_d = s->n_prev = 0;
  s->sigma = 0.0;
  s->u0 = s->y0 = s->eps = s->d_high = s->d_low = s->relay_start = 0;
  s->high = 0;
  s->e_prev = s->e_max = s->e_min = s->integral = s->integral_on = s->timeout = 0;
  s->k_high = s->k_low = -1;
  s->n_cycles = 0;
  s->n_changes = 0;
  s->last_change = 0.0;
  s->restarts = 0;
  s->end_step = -1;
  s->end = PIDLAB_RELAY_END_NONE;
  s->load_change_s = -1.0;
  return 0;
}

static void start_hold(pidlab_relay *s) {
  s->phase = PIDLAB_RELAY_HOLD;
  s->n_u = s->n_d = 0;
  s->n_prev = 0;
  s->hold_start = s->k;
  s->sum_u = s->sum_y = s->sum_d = 0;
  s->sum_d2 = 0;
}

static int64_t after(pidlab_relay *s, pidlab_q r, pidlab_q y) {
  pidlab_q u = 0;
  if (!s->has_pid) return s->phase == PIDLAB_RELAY_HOLD ? s->u0_config : s->u0;
  pidlab_pid_step(s->pid, r, y, &u);
  return u;
}

static void end(pidlab_relay *s, pidlab_relay_phase phase, pidlab_relay_end why) {
  s->phase = phase;
  s->end_step = s->k;
  s->end = why;
}

static double tolerance(const pidlab_relay *s, const pidlab_relay_cycle *c) {
  return s->config.tolerance + (amplitude(c) > 0.0 ? 2.0 * s->sigma / amplitude(c) : 0.0);
}

static void end_hold(pidlab_relay *s, int64_t r, int64_t y) {
  double sigma_d = 0.0;
  s->u0 = s->has_pid && s->n_u > 0 ? round_clamp((double)s->sum_u / (double)s->n_u, -PIDLAB_RELAY_TOP,
                                                 PIDLAB_RELAY_TOP - 1.0)
                                   : s->u0_config;
  s->y0 = s->n_u > 0 ? round_clamp((double)s->sum_y / (double)s->n_u, -PIDLAB_RELAY_TOP, PIDLAB_RELAY_TOP - 1.0)
                     : r;
  if (s->n_d > 1) {
    const double n = (double)s->n_d;
    const double sum = (double)s->sum_d;
    const double var = ((double)s->sum_d2 - sum * sum / n) / (n - 1.0);
    sigma_d = var > 0.0 ? sqrt(var / 6.0) : 0.0;
  }
  s->sigma = sigma_d * ldexp(s->qy, PIDLAB_RELAY_SHIFT);
  s->eps = s->hyst + round_clamp(s->config.noise_multiple * ldexp(sigma_d, PIDLAB_RELAY_SHIFT), 0.0,
                                 PIDLAB_RELAY_TOP);
  s->d_high = min64(s->dh, s->out_max - s->u0);
  s->d_low = min64(s->dl, s->u0 - s->out_min);
  if (s->d_high <= 0 || s->d_low <= 0) {
    end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_NO_ROOM);
    return;
  }
  s->phase = PIDLAB_RELAY_RELAY;
  s->relay_start = s->k;
  s->high = y - s->y0 < 0;
  s->e_prev = y - s->y0;
  s->k_high = s->k_low = -1;
  s->integral = 0;
  s->f = s->f_max = s->f_min = 0;
  s->cycle_steps = 0;
  s->quiet = 0;
  s->timeout = 0;
  s->n_cycles = 0;
  s->n_changes = 0;
}

static void on_cycle(pidlab_relay *s, const pidlab_relay_cycle *c, int quiet) {
  long i, n;
  double p_sum = 0.0, a_sum = 0.0;
  if (s->sigma > 0.0 && quiet) {
    if (++s->quiet >= PIDLAB_RELAY_QUIET_CYCLES) {
      end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_NOISE);
      return;
    }
  } else {
    s->quiet = 0;
  }
  if (s->n_cycles > 0) {
    const pidlab_relay_cycle *p = back(s, 0);
    double change = fabs(period(c) - period(p)) / period(p);
    const double da = fabs(amplitude(c) - amplitude(p)) / amplitude(p);
    const double dd = fabs(c->t_on_s / period(c) - p->t_on_s / period(p));
    if (change < da) change = da;
    if (change < dd) change = dd;
    if (s->n_changes >= 2 && change > 5.0 * tolerance(s, p) && change > 2.0 * s->last_change) {
      s->load_change_s = c->start_s;
      if (!s->has_pid) {
        end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_LOAD_CHANGE);
        return;
      }
      if (s->restarts >= s->config.max_restarts) {
        end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_TOO_MANY_RESTARTS);
        return;
      }
      ++s->restarts;
      start_hold(s);
      return;
    }
    s->last_change = change;
  } else {
    s->last_change = 0.0;
  }
  ++s->n_changes;
  s->cycles[s->n_cycles % PIDLAB_RELAY_MAX_CYCLES] = *c;
  ++s->n_cycles;
  n = 3.0 * s->sigma > 0.01 * amplitude(c) && s->config.settled_cycles < PIDLAB_RELAY_NOISY_SETTLED_CYCLES
          ? PIDLAB_RELAY_NOISY_SETTLED_CYCLES
          : s->config.settled_cycles;
  if (s->n_cycles < n + 1) return; /* the first cycle is the approach */
  for (i = 0; i < n; ++i) {
    p_sum += period(back(s, i)) / (double)n;
    a_sum += amplitude(back(s, i)) / (double)n;
  }
  for (i = 0; i < n; ++i) {
    const pidlab_relay_cycle *k = back(s, i);
    if (!(fabs(period(k) - p_sum) <= tolerance(s, k) * p_sum) ||
        !(fabs(amplitude(k) - a_sum) <= tolerance(s, k) * a_sum))
      return;
  }
  end(s, PIDLAB_RELAY_DONE, PIDLAB_RELAY_END_CONVERGED);
}

static int64_t relay_step(pidlab_relay *s, pidlab_q r, pidlab_q y) {
  const int64_t e = (int64_t)y - s->y0;
  if (s->k > s->relay_start) {
    if (!((e < 0 ? -e : e) <= s->y_limit)) {
      end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_Y_LIMIT);
      return after(s, r, y);
    }
    s->f += quiet_shift(e - s->f);
    if (s->k_high >= 0) {
      s->integral += e + s->e_prev;
      s->e_max = max64(s->e_max, e);
      s->e_min = min64(s->e_min, e);
      s->f_max = max64(s->f_max, s->f);
      s->f_min = min64(s->f_min, s->f);
      ++s->cycle_steps;
    }
    if (!s->high && e < -s->eps) {
      const int complete = s->k_high >= 0 && s->k_low > s->k_high;
      const int64_t period_k = s->k - s->k_high;
      const int quiet = s->cycle_steps >= PIDLAB_RELAY_QUIET_MIN_STEPS && 5 * (s->f_max - s->f_min) < 6 * s->eps;
      pidlab_relay_cycle c = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
      if (complete) {
        c.start_s = (double)s->k_high * s->dt_s;
        c.t_on_s = (double)(s->k_low - s->k_high) * s->dt_s;
        c.t_off_s = (double)(s->k - s->k_low) * s->dt_s;
        c.e_max = (double)s->e_max * s->qy;
        c.e_min = (double)s->e_min * s->qy;
        c.integral_e = (double)s->integral * (0.5 * s->dt_s * s->qy);
        c.integral_on_e = (double)s->integral_on * (0.5 * s->dt_s * s->qy);
      }
      s->high = 1;
      s->k_high = s->k;
      s->k_low = -1;
      s->integral = 0;
      s->e_max = s->e_min = e;
      s->f_max = s->f_min = s->f;
      s->cycle_steps = 0;
      if (complete) {
        const long before = s->n_cycles;
        on_cycle(s, &c, quiet);
        if (s->phase != PIDLAB_RELAY_RELAY) return after(s, r, y);
        if (s->n_cycles > before) { /* the longest cycle's periods: noise cuts a cycle short */
          const int64_t timeout = (int64_t)floor(s->config.timeout_periods * (double)period_k);
          if (timeout > s->timeout) s->timeout = timeout;
        }
      }
    } else if (s->high && e > s->eps) {
      s->high = 0;
      if (s->k_high >= 0) {
        s->k_low = s->k;
        s->integral_on = s->integral;
      }
    }
    if (s->n_cycles > 0 && s->k - s->relay_start > s->timeout) {
      end(s, PIDLAB_RELAY_ABORTED, PIDLAB_RELAY_END_TIMEOUT);
      return after(s, r, y);
    }
  }
  s->e_prev = e;
  return s->u0 + (s->high ? s->d_high : -s->d_low);
}

pidlab_q pidlab_relay_step(pidlab_relay *s, pidlab_q r, pidlab_q y) {
  int64_t u;
  if (s->first) {
    s->first = 0;
    s->k = 0;
    start_hold(s);
  } else {
    ++s->k;
  }
  if (s->phase == PIDLAB_RELAY_HOLD && s->k - s->hold_start >= s->hold_steps) end_hold(s, r, y);
  if (s->phase == PIDLAB_RELAY_RELAY) return (pidlab_q)relay_step(s, r, y);
  if (s->phase != PIDLAB_RELAY_HOLD) return (pidlab_q)after(s, r, y);
  u = after(s, r, y);
  if (2 * (s->k - s->hold_start) >= s->hold_steps) {
    s->sum_u += u;
    s->sum_y += y;
    ++s->n_u;
    if (s->n_prev >= 2) {
      const int64_t d = shift_round((int64_t)y - 2 * s->y_prev + s->y_prev2);
      const uint64_t d2 = (uint64_t)(d * d);
      s->sum_d += d;
      s->sum_d2 = d2 > UINT64_MAX - s->sum_d2 ? UINT64_MAX : s->sum_d2 + d2;
      ++s->n_d;
    }
    s->y_prev2 = s->y_prev;
    s->y_prev = y;
    ++s->n_prev;
  }
  return (pidlab_q)u;
}

pidlab_relay_phase pidlab_relay_get_phase(const pidlab_relay *s) { return s->phase; }
pidlab_relay_end pidlab_relay_get_end(const pidlab_relay *s) { return s->end; }
long pidlab_relay_cycle_count(const pidlab_relay *s) { return s->n_cycles; }
const pidlab_relay_cycle *pidlab_relay_cycle_at(const pidlab_relay *s, long i) {
  if (i < 0 || i >= s->n_cycles || s->n_cycles - i > PIDLAB_RELAY_MAX_CYCLES) return 0;
  return &s->cycles[i % PIDLAB_RELAY_MAX_CYCLES];
}
)C";

}  // namespace pidlab::controller_export::internal
