/* The generated relay autotune (pidlab_relay.c, double or fixed point)
 * behind a double interface, for tests/export_test.cc: r and y are rounded
 * to the fixed-point module's grid as pidlab-controller-c does
 * (controller_role_c.c), u read back in the loop's units. Compiled with
 * shim_real.c or shim_fixed.c, whose shim_new gives the PID. */
#include <math.h>
#include <stdlib.h>

#include "pidlab_relay.h"

void *shim_relay_new(void *pid, const double *v, int settled_cycles, int max_restarts) {
  pidlab_relay_config c;
  pidlab_relay *relay = (pidlab_relay *)malloc(sizeof(pidlab_relay));
  if (!relay) return NULL;
  c.hold_s = v[0];
  c.u0 = v[1];
  c.amplitude = v[2];
  c.bias = v[3];
  c.hysteresis = v[4];
  c.noise_multiple = v[5];
  c.y_limit = v[6];
  c.tolerance = v[7];
  c.timeout_periods = v[8];
  c.settled_cycles = settled_cycles;
  c.max_restarts = max_restarts;
  if (pidlab_relay_init(relay, &c, (pidlab_pid *)pid) != 0) {
    free(relay);
    return NULL;
  }
  return relay;
}

void shim_relay_free(void *relay) { free(relay); }

#ifdef PIDLAB_Q_BITS
static pidlab_q shim_relay_q(double v) {
  const double top = ldexp(1.0, PIDLAB_Q_BITS),
               q = floor(ldexp(v / PIDLAB_INPUT_FULL_SCALE, PIDLAB_Q_BITS) + 0.5);
  return (pidlab_q)(q < -top ? -top : (q > top - 1.0 ? top - 1.0 : q));
}
#endif

double shim_relay_step(void *relay, double t_s, double r, double y) {
#ifdef PIDLAB_Q_BITS
  (void)t_s;
  return (double)pidlab_relay_step((pidlab_relay *)relay, shim_relay_q(r), shim_relay_q(y)) *
         ldexp(PIDLAB_OUTPUT_FULL_SCALE, -PIDLAB_Q_BITS);
#else
  return pidlab_relay_step((pidlab_relay *)relay, t_s, r, y);
#endif
}

int shim_relay_phase(void *relay) { return (int)pidlab_relay_get_phase((pidlab_relay *)relay); }
long shim_relay_cycle_count(void *relay) { return pidlab_relay_cycle_count((pidlab_relay *)relay); }
int shim_relay_cycle(void *relay, long i, double *out) {
  const pidlab_relay_cycle *c = pidlab_relay_cycle_at((pidlab_relay *)relay, i);
  if (!c) return 0;
  out[0] = c->start_s;
  out[1] = c->t_on_s;
  out[2] = c->t_off_s;
  out[3] = c->e_max;
  out[4] = c->e_min;
  out[5] = c->integral_e;
  out[6] = c->integral_on_e;
  return 1;
}
