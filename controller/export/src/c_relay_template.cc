// The generated C of the relay autotune (`pidlab export --autotune`, double):
// pidlab_relay.h and pidlab_relay.c, controller/relay.h's RelayTuner line for
// line, in the same operation order, over the exported PID as the previous
// loop. With the double module its inputs equal RelayTuner's bit for bit
// (tests/export_test.cc, integration.autotune.firmware).

#include "templates.h"

namespace pidlab::controller_export::internal {

const char* const kRelayHeader =
    R"C(/* pidlab_relay.h: the relay autotune, exported by pidlab export --autotune.
 *
 * The state machine pidlab-controller runs in a relay episode
 * (docs/autotune.md), over the exported PID as the loop in place:
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
 * Read the cycles (pidlab_relay_cycle_at) to estimate the process the way
 * pidlab autotune does. Uses <math.h>: sqrt. Double only. */
#ifndef PIDLAB_RELAY_H_
#define PIDLAB_RELAY_H_

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

typedef struct {
  double start_s, t_on_s, t_off_s, e_max, e_min, integral_e, integral_on_e;
} pidlab_relay_cycle;

/* Treat as opaque; read it with the functions below. */
typedef struct {
  pidlab_relay_config config;
  pidlab_pid *pid; /* the previous loop */
  int has_pid;
  double out_min, out_max;
  pidlab_relay_phase phase;
  int first;
  double hold_start_s, sum_u, sum_y, sum_d, sum_d2, y_prev, y_prev2;
  long n_u, n_d, n_prev;
  double u0, y0, sigma, eps, d_high, d_low, relay_start_s;
  int high;
  double t_prev, e_prev, t_high, t_low, e_max, e_min, integral, integral_on;
  double f, f_max, f_min; /* e smoothed (f += (e - f) / 16), its extremes in the cycle */
  long cycle_steps;
  int quiet; /* cycles in a row whose smoothed e stayed inside the hysteresis */
  double longest_period; /* since the relay's start: the timeout counts its periods */
  pidlab_relay_cycle cycles[PIDLAB_RELAY_MAX_CYCLES]; /* a ring: the last ones */
  long n_cycles;                                      /* since the relay's last start */
  long n_changes;
  double last_change;
  int restarts;
  double end_s;
  pidlab_relay_end end;
  double load_change_s; /* the last load change's cycle start, s; -1: none */
} pidlab_relay;

/* `pid` is the previous loop, initialised (pidlab_pid_init) and not stepped
 * elsewhere while the relay runs; its output limits are the relay's range.
 * 0 on success, -1 if a value is out of range (nothing changed). */
int pidlab_relay_init(pidlab_relay *relay, const pidlab_relay_config *config, pidlab_pid *pid);

/* One sample at time t_s (strictly increasing) with setpoint r and a finite
 * measurement y: the input to apply until the next one. */
double pidlab_relay_step(pidlab_relay *relay, double t_s, double r, double y);

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

const char* const kRelaySource =
    R"C(/* pidlab_relay.c: the relay autotune, exported by pidlab export --autotune.
 * See pidlab_relay.h. C99 and <math.h>. */
#include "pidlab_relay.h"

#include <math.h>

/* std::max and std::min as C++ defines them: the first unless the second is
 * larger (smaller). */
static double max2(double a, double b) { return a < b ? b : a; }
static double min2(double a, double b) { return b < a ? b : a; }
static double clip(double u, double lo, double hi) { return min2(max2(u, lo), hi); }
static double period(const pidlab_relay_cycle *c) { return c->t_on_s + c->t_off_s; }
static double amplitude(const pidlab_relay_cycle *c) { return 0.5 * (c->e_max - c->e_min); }
static const pidlab_relay_cycle *back(const pidlab_relay *s, long i) {
  return &s->cycles[(s->n_cycles - 1 - i) % PIDLAB_RELAY_MAX_CYCLES];
}

int pidlab_relay_init(pidlab_relay *s, const pidlab_relay_config *c, pidlab_pid *pid) {
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
  s->out_min = pid->config.has_output_min ? pid->config.output_min : -INFINITY;
  s->out_max = pid->config.has_output_max ? pid->config.output_max : INFINITY;
  s->phase = PIDLAB_RELAY_HOLD;
  s->first = 1;
  s->hold_start_s = s->sum_u = s->sum_y = s->sum_d = s->sum_d2 = s->y_prev = s->y_prev2 = 0.0;
  s->n_u = s->n_d = s->n_prev = 0;
  s->u0 = s->y0 = s->sigma = s->eps = s->d_high = s->d_low = 0.0;
  s->relay_start_s = -1.0;
  s->high = 0;
  s->t_prev = s->e_prev = 0.0;
  s->t_high = s->t_low = -1.0;
  s->e_max = s->e_min = s->integral = s->integral_on = 0.0;
  s->n_cycles = 0;
  s->n_changes = 0;
  s->last_change = 0.0;
  s->restarts = 0;
  s->end_s = -1.0;
  s->end = PIDLAB_RELAY_END_NONE;
  s->load_change_s = -1.0;
  return 0;
}

static void start_hold(pidlab_relay *s, double t) {
  s->phase = PIDLAB_RELAY_HOLD;
  s->hold_start_s = t;
  s->sum_u = s->sum_y = s->sum_d = s->sum_d2 = 0.0;
  s->n_u = s->n_d = 0;
  s->n_prev = 0;
}

static double after(pidlab_relay *s, double r, double y) {
  double u = 0.0;
  if (!s->has_pid) return clip(s->phase == PIDLAB_RELAY_HOLD ? s->config.u0 : s->u0, s->out_min, s->out_max);
  pidlab_pid_step(s->pid, r, y, &u);
  return u;
}

static void end(pidlab_relay *s, pidlab_relay_phase phase, double t, pidlab_relay_end why) {
  s->phase = phase;
  s->end_s = t;
  s->end = why;
}

static double tolerance(const pidlab_relay *s, const pidlab_relay_cycle *c) {
  return s->config.tolerance + (amplitude(c) > 0.0 ? 2.0 * s->sigma / amplitude(c) : 0.0);
}

static void end_hold(pidlab_relay *s, double t, double r, double y) {
  s->u0 = s->has_pid && s->n_u > 0 ? s->sum_u / (double)s->n_u : clip(s->config.u0, s->out_min, s->out_max);
  s->y0 = s->n_u > 0 ? s->sum_y / (double)s->n_u : r;
  s->sigma = 0.0;
  if (s->n_d > 1) {
    const double n = (double)s->n_d;
    const double var = (s->sum_d2 - s->sum_d * s->sum_d / n) / (n - 1.0);
    s->sigma = var > 0.0 ? sqrt(var / 6.0) : 0.0;
  }
  s->eps = s->config.hysteresis + s->config.noise_multiple * s->sigma;
  s->d_high = min2(s->config.amplitude + s->config.bias, s->out_max - s->u0);
  s->d_low = min2(s->config.amplitude - s->config.bias, s->u0 - s->out_min);
  if (!(s->d_high > 0.0) || !(s->d_low > 0.0) || !isfinite(s->u0)) {
    end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_NO_ROOM);
    return;
  }
  s->phase = PIDLAB_RELAY_RELAY;
  s->relay_start_s = t;
  s->high = y - s->y0 < 0.0;
  s->t_prev = t;
  s->e_prev = y - s->y0;
  s->t_high = s->t_low = -1.0;
  s->integral = 0.0;
  s->f = s->f_max = s->f_min = 0.0;
  s->cycle_steps = 0;
  s->quiet = 0;
  s->longest_period = 0.0;
  s->n_cycles = 0;
  s->n_changes = 0;
}

static void on_cycle(pidlab_relay *s, const pidlab_relay_cycle *c, double t, int quiet) {
  long i, n;
  double p_sum = 0.0, a_sum = 0.0;
  if (s->sigma > 0.0 && quiet) {
    if (++s->quiet >= PIDLAB_RELAY_QUIET_CYCLES) {
      end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_NOISE);
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
        end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_LOAD_CHANGE);
        return;
      }
      if (s->restarts >= s->config.max_restarts) {
        end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_TOO_MANY_RESTARTS);
        return;
      }
      ++s->restarts;
      start_hold(s, t);
      return;
    }
    s->last_change = change;
  } else {
    s->last_change = 0.0;
  }
  ++s->n_changes;
  s->cycles[s->n_cycles % PIDLAB_RELAY_MAX_CYCLES] = *c;
  ++s->n_cycles;
  if (period(c) > s->longest_period) s->longest_period = period(c);
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
  end(s, PIDLAB_RELAY_DONE, t, PIDLAB_RELAY_END_CONVERGED);
}

static double relay_step(pidlab_relay *s, double t, double r, double y) {
  const double e = y - s->y0;
  if (t > s->relay_start_s) {
    if (!(fabs(e) <= s->config.y_limit)) {
      end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_Y_LIMIT);
      return after(s, r, y);
    }
    s->f += (e - s->f) * 0.0625;
    if (s->t_high >= 0.0) {
      s->integral += 0.5 * (e + s->e_prev) * (t - s->t_prev);
      s->e_max = max2(s->e_max, e);
      s->e_min = min2(s->e_min, e);
      s->f_max = max2(s->f_max, s->f);
      s->f_min = min2(s->f_min, s->f);
      ++s->cycle_steps;
    }
    if (!s->high && e < -s->eps) {
      const int complete = s->t_high >= 0.0 && s->t_low > s->t_high;
      const int quiet = s->cycle_steps >= PIDLAB_RELAY_QUIET_MIN_STEPS && 0.5 * (s->f_max - s->f_min) < 0.6 * s->eps;
      pidlab_relay_cycle c = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
      if (complete) {
        c.start_s = s->t_high;
        c.t_on_s = s->t_low - s->t_high;
        c.t_off_s = t - s->t_low;
        c.e_max = s->e_max;
        c.e_min = s->e_min;
        c.integral_e = s->integral;
        c.integral_on_e = s->integral_on;
      }
      s->high = 1;
      s->t_high = t;
      s->t_low = -1.0;
      s->integral = 0.0;
      s->e_max = s->e_min = e;
      s->f_max = s->f_min = s->f;
      s->cycle_steps = 0;
      if (complete) on_cycle(s, &c, t, quiet);
      if (s->phase != PIDLAB_RELAY_RELAY) return after(s, r, y);
    } else if (s->high && e > s->eps) {
      s->high = 0;
      if (s->t_high >= 0.0) {
        s->t_low = t;
        s->integral_on = s->integral;
      }
    }
    if (s->n_cycles > 0 && t - s->relay_start_s > s->config.timeout_periods * s->longest_period) {
      end(s, PIDLAB_RELAY_ABORTED, t, PIDLAB_RELAY_END_TIMEOUT);
      return after(s, r, y);
    }
  }
  s->t_prev = t;
  s->e_prev = e;
  return s->u0 + (s->high ? s->d_high : -s->d_low);
}

double pidlab_relay_step(pidlab_relay *s, double t, double r, double y) {
  double u;
  if (s->first) {
    s->first = 0;
    start_hold(s, t);
  }
  if (s->phase == PIDLAB_RELAY_HOLD && t - s->hold_start_s >= s->config.hold_s) end_hold(s, t, r, y);
  if (s->phase == PIDLAB_RELAY_RELAY) return relay_step(s, t, r, y);
  if (s->phase != PIDLAB_RELAY_HOLD) {
    if (s->has_pid) return after(s, r, y);
    return clip(s->u0, s->out_min, s->out_max);
  }
  u = after(s, r, y);
  if (2.0 * (t - s->hold_start_s) >= s->config.hold_s) {
    s->sum_u += u;
    s->sum_y += y;
    ++s->n_u;
    if (s->n_prev >= 2) {
      const double d = y - 2.0 * s->y_prev + s->y_prev2;
      s->sum_d += d;
      s->sum_d2 += d * d;
      ++s->n_d;
    }
    s->y_prev2 = s->y_prev;
    s->y_prev = y;
    ++s->n_prev;
  }
  return u;
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
