/* pidlab-controller-c: the controller role of the trio in C, its PID the
 * module `pidlab export --scalar double` generates (pidlab_pid.c), its
 * messages lcm-gen -c's, its transport liblcm's C API. It takes
 * pidlab-controller's place next to `pidlab launch --roles plant,disturbance`
 * and answers the plant as controller/src/controller_role.cc does
 * (docs/protocol.md; examples/python_controller.py is the same in Python):
 * PING -> ALIVE, a configuration -> CONFIG_ACK and a fresh controller,
 * y_k -> u_k once, a resent y_k -> the same u_k again.
 *
 *   pidlab-controller-c [--lcm-url udpm://GROUP:PORT?ttl=N] [--channel-prefix P] [--verbose]
 *                       [--print-configs] [--print-relay]
 *
 * --print-configs writes every configuration it accepts to stdout as one JSON
 * line, every field of the message by its .lcm name (the X-macro
 * <pidlab/lcmt_episode_config_fields.h>): what this controller saw.
 * --print-relay writes each relay episode's end to stdout as one JSON line:
 * the end code and its own cycles (pidlab_relay_cycle_at), each
 * [start_s, t_on_s, t_off_s, e_max, e_min, integral_e, integral_on_e].
 *
 * Built around a fixed-point module (pidlab export --scalar q31|q15, whose
 * pidlab_pid.h defines PIDLAB_Q_BITS) it rounds r and y to the module's
 * grid, floor(v 2^bits / X + 0.5) clipped to the integer type, and sends
 * u = q U 2^-bits (docs/autotune.md, "In the firmware").
 *
 * Not supported: --auth-key (HMAC tags, docs/security.md). */
#include <lcm/lcm.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/time.h>
#include <unistd.h>

#include "pidlab/lcmt_episode_config_fields.h"
#include "pidlab_lcmt_control_command.h"
#include "pidlab_lcmt_episode_config.h"
#include "pidlab_lcmt_plant_output.h"
#include "pidlab_lcmt_ready.h"
#include "pidlab_pid.h"
#ifdef PIDLAB_RELAY /* the relay autotune: pidlab export --autotune's pidlab_relay.c beside the PID */
#include "pidlab_relay.h"
#endif

/* transport/transport.h: PLANT_OUTPUT on the base port + 1, CONTROL on + 2. */
enum { kPlantOutputLane = 1, kControlLane = 2, kLanes = 3 };
#define MAX_EPISODE_STEPS 50000000LL
#define MAX_GAIN 1e12

typedef struct {
  lcm_t *lcm[kLanes];
  char prefix[64];
  int64_t episode_id; /* current episode, 0 before the first */
  int have_episode;
  int64_t total_steps, expected;
  double reference;
  pidlab_pid pid;
#ifdef PIDLAB_RELAY
  pidlab_relay relay; /* a relay episode (controller_mode "relay", docs/autotune.md) */
#endif
  int relay_on;
  int relay_printed;
  pidlab_lcmt_control_command last;
  int have_last;
  long episodes, commands, foreign, duplicates, bad_configs, conflicts;
  int print_configs, print_relay;
} controller;

static volatile sig_atomic_t stop = 0;
static void on_signal(int signo) {
  (void)signo;
  stop = 1;
}

static int64_t now_utime(void) {
  struct timeval tv;
  gettimeofday(&tv, NULL);
  return (int64_t)tv.tv_sec * 1000000 + tv.tv_usec;
}

static void channel(const controller *c, const char *name, char *out, size_t size) {
  snprintf(out, size, "%s%s", c->prefix, name);
}

static void ack(controller *c, int64_t episode_id) {
  char name[96];
  char role[] = "controller", detail[] = "";
  pidlab_lcmt_ready r;
  memset(&r, 0, sizeof r);
  r.utime = now_utime();
  r.episode_id = episode_id;
  r.step = -1;
  r.state = episode_id == 0 ? PIDLAB_LCMT_READY_ALIVE : PIDLAB_LCMT_READY_CONFIG_ACK;
  r.role = role;
  r.pid = (int32_t)getpid();
  r.detail = detail;
  channel(c, "READY", name, sizeof name);
  pidlab_lcmt_ready_publish(c->lcm[0], name, &r);
}

static int finite(double x) { return x - x == 0.0; }

#ifdef PIDLAB_Q_BITS
/* A value in the loop's units on the module's input grid, and a pidlab_q
 * output back in the loop's units (RelayTuner's QIn, relay.cc). */
static pidlab_q to_q_in(double v) {
  const double top = ldexp(1.0, PIDLAB_Q_BITS),
               q = floor(ldexp(v / PIDLAB_INPUT_FULL_SCALE, PIDLAB_Q_BITS) + 0.5);
  return (pidlab_q)(q < -top ? -top : (q > top - 1.0 ? top - 1.0 : q));
}
static double from_q_out(pidlab_q u) { return (double)u * ldexp(PIDLAB_OUTPUT_FULL_SCALE, -PIDLAB_Q_BITS); }
#endif

/* The controller's share of transport::ParseEpisodeConfig: what it uses. */
static const char *config_error(const pidlab_lcmt_episode_config *m) {
  if (m->episode_id == 0) return "episode id 0";
  if (!(finite(m->kp) && fabs(m->kp) <= MAX_GAIN && finite(m->ki) && fabs(m->ki) <= MAX_GAIN && finite(m->kd) &&
        fabs(m->kd) <= MAX_GAIN))
    return "a gain is not finite and at most 1e12 in size";
  /* One sign: all >= 0 (direct acting) or all <= 0 (reverse acting). */
  if (!((m->kp >= 0 && m->ki >= 0 && m->kd >= 0) || (m->kp <= 0 && m->ki <= 0 && m->kd <= 0)))
    return "the gains differ in sign";
  if (!finite(m->reference)) return "reference not finite";
  if (!(finite(m->dt_s) && m->dt_s > 0)) return "dt not positive and finite";
  if (m->total_steps < 1 || m->total_steps > MAX_EPISODE_STEPS) return "total steps out of [1, 5e7]";
  if (!(finite(m->derivative_filter_s) && m->derivative_filter_s >= 0)) return "derivative filter";
  if (m->output_min != m->output_min || m->output_max != m->output_max || !(m->output_min < m->output_max))
    return "output limits";
  if (strcmp(m->anti_windup, "none") && strcmp(m->anti_windup, "clamping") &&
      strcmp(m->anti_windup, "back-calculation"))
    return "anti-windup unknown";
  if (!strcmp(m->anti_windup, "back-calculation") &&
      !(finite(m->back_calculation_gain) && m->back_calculation_gain > 0))
    return "back-calculation gain";
  if (strcmp(m->derivative_on, "error") && strcmp(m->derivative_on, "measurement"))
    return "derivative-on unknown";
  if (!(finite(m->setpoint_weight_b) && m->setpoint_weight_b >= 0 && m->setpoint_weight_b <= 1 &&
        finite(m->setpoint_weight_c) && m->setpoint_weight_c >= 0 && m->setpoint_weight_c <= 1))
    return "setpoint weights not in [0, 1]";
  if (!(finite(m->setpoint_filter_s) && m->setpoint_filter_s >= 0)) return "setpoint filter not >= 0";
  if (strcmp(m->integral, "backward-euler") && strcmp(m->integral, "forward-euler") &&
      strcmp(m->integral, "trapezoidal"))
    return "integral unknown";
  if (strcmp(m->controller_mode, "") && strcmp(m->controller_mode, "pid") &&
      strcmp(m->controller_mode, "relay"))
    return "controller mode unknown";
#ifndef PIDLAB_RELAY
  if (!strcmp(m->controller_mode, "relay"))
    return "a relay episode: built without the relay (-DPIDLAB_RELAY, pidlab export --autotune's "
           "pidlab_relay.c)";
#endif
  return NULL;
}

#ifdef PIDLAB_RELAY

/* The relay's options as the message carries them (RelayTuneOptions). */
static void to_relay_config(const pidlab_lcmt_episode_config *m, pidlab_relay_config *r) {
  memset(r, 0, sizeof *r);
  r->hold_s = m->relay_hold_s;
  r->u0 = m->relay_u0;
  r->amplitude = m->relay_amplitude;
  r->bias = m->relay_bias;
  r->hysteresis = m->relay_hysteresis;
  r->noise_multiple = m->relay_noise_multiple;
  r->y_limit = m->relay_y_limit;
  r->settled_cycles =
      m->relay_settled_cycles < -1 || m->relay_settled_cycles > 1000 ? -1 : (int)m->relay_settled_cycles;
  r->tolerance = m->relay_tolerance;
  r->timeout_periods = m->relay_timeout_periods;
  r->max_restarts =
      m->relay_max_restarts < -1 || m->relay_max_restarts > 1000 ? -1 : (int)m->relay_max_restarts;
}
#endif

/* The episode's configuration as the exported module's: the setpoint weights
 * b and c as the message carries them (c = 0 is derivative on measurement),
 * infinite limits are none. */
static void to_config(const pidlab_lcmt_episode_config *m, pidlab_pid_config *p) {
  memset(p, 0, sizeof *p);
  p->kp = m->kp;
  p->ki = m->ki;
  p->kd = m->kd;
  p->tf = m->derivative_filter_s;
  p->setpoint_weight_b = m->setpoint_weight_b;
  p->setpoint_weight_c = m->setpoint_weight_c;
  p->setpoint_filter_s = m->setpoint_filter_s;
  p->dt_s = m->dt_s;
#ifdef PIDLAB_Q_BITS /* fixed point: finite limits (init refuses others) */
  p->output_min = m->output_min;
  p->output_max = m->output_max;
#else
  p->has_output_min = finite(m->output_min);
  p->output_min = p->has_output_min ? m->output_min : 0.0;
  p->has_output_max = finite(m->output_max);
  p->output_max = p->has_output_max ? m->output_max : 0.0;
#endif
  p->anti_windup = !strcmp(m->anti_windup, "none")       ? PIDLAB_ANTI_WINDUP_NONE
                   : !strcmp(m->anti_windup, "clamping") ? PIDLAB_ANTI_WINDUP_CLAMPING
                                                         : PIDLAB_ANTI_WINDUP_BACK_CALCULATION;
  p->back_calculation_gain = m->back_calculation_gain;
  p->integral = !strcmp(m->integral, "forward-euler") ? PIDLAB_INTEGRAL_FORWARD_EULER
                : !strcmp(m->integral, "trapezoidal") ? PIDLAB_INTEGRAL_TRAPEZOIDAL
                                                      : PIDLAB_INTEGRAL_BACKWARD_EULER;
}

/* JSON as Python's json module reads it (Infinity, -Infinity, NaN). */
static void print_double(double v) {
  if (v != v)
    fputs("NaN", stdout);
  else if (isinf(v))
    fputs(v > 0 ? "Infinity" : "-Infinity", stdout);
  else
    printf("%.17g", v);
}

static void print_string(const char *s) {
  putchar('"');
  for (; *s; ++s) {
    if (*s == '"' || *s == '\\')
      printf("\\%c", *s);
    else if ((unsigned char)*s < 0x20)
      printf("\\u%04x", (unsigned)*s);
    else
      putchar(*s);
  }
  putchar('"');
}

/* Every field of the configuration, by its .lcm name, as one JSON line. */
static void print_config(const pidlab_lcmt_episode_config *m) {
  const char *sep = "{";
  int32_t k;
#define PRINT_D(name)               \
  printf("%s\"" #name "\": ", sep); \
  print_double(m->name);            \
  sep = ", ";
#define PRINT_I(name)                                       \
  printf("%s\"" #name "\": %lld", sep, (long long)m->name); \
  sep = ", ";
#define PRINT_S(name)               \
  printf("%s\"" #name "\": ", sep); \
  print_string(m->name);            \
  sep = ", ";
#define PRINT_A(name, count)                                            \
  printf("%s\"" #count "\": %d, \"" #name "\": [", sep, (int)m->count); \
  for (k = 0; k < m->count; ++k) {                                      \
    if (k) fputs(", ", stdout);                                         \
    print_double(m->name[k]);                                           \
  }                                                                     \
  putchar(']');                                                         \
  sep = ", ";
#define PRINT_N(name)                               \
  printf("%s\"" #name "\": %d", sep, (int)m->name); \
  sep = ", ";
  PIDLAB_LCMT_EPISODE_CONFIG_FIELDS(PRINT_D, PRINT_I, PRINT_S, PRINT_A, PRINT_N)
#undef PRINT_D
#undef PRINT_I
#undef PRINT_S
#undef PRINT_A
#undef PRINT_N
  fputs("}\n", stdout);
  fflush(stdout);
}

#ifdef PIDLAB_RELAY
/* The relay's end and its cycles, one JSON line. */
static void print_relay_end(const controller *c) {
  long i;
  printf("{\"episode_id\": %lld, \"phase\": %d, \"end\": %d, \"cycles\": [", (long long)c->episode_id,
         (int)pidlab_relay_get_phase(&c->relay), (int)pidlab_relay_get_end(&c->relay));
  for (i = 0; i < pidlab_relay_cycle_count(&c->relay); ++i) {
    const pidlab_relay_cycle *k = pidlab_relay_cycle_at(&c->relay, i);
    if (!k) continue;
    printf("%s[", i ? ", " : "");
    print_double(k->start_s);
    fputs(", ", stdout);
    print_double(k->t_on_s);
    fputs(", ", stdout);
    print_double(k->t_off_s);
    fputs(", ", stdout);
    print_double(k->e_max);
    fputs(", ", stdout);
    print_double(k->e_min);
    fputs(", ", stdout);
    print_double(k->integral_e);
    fputs(", ", stdout);
    print_double(k->integral_on_e);
    putchar(']');
  }
  fputs("]}\n", stdout);
  fflush(stdout);
}
#endif

static void on_config(const lcm_recv_buf_t *rbuf, const char *ch, const pidlab_lcmt_episode_config *m,
                      void *user) {
  controller *c = (controller *)user;
  pidlab_pid_config config;
  const char *error;
  (void)rbuf;
  (void)ch;
  if (m->episode_id == c->episode_id && c->episode_id != 0) {
    ++c->duplicates;
    ack(c, c->episode_id); /* our first acknowledgement may have been lost */
    return;
  }
  error = config_error(m);
  to_config(m, &config);
  if (!error && pidlab_pid_init(&c->pid, &config) != PIDLAB_PID_OK)
    error = "the module refused the configuration";
  c->relay_on = !error && !strcmp(m->controller_mode, "relay");
#ifdef PIDLAB_RELAY
  if (c->relay_on) {
    pidlab_relay_config relay;
    to_relay_config(m, &relay);
    if (pidlab_relay_init(&c->relay, &relay, &c->pid) != 0) {
      error = "the relay's options are out of range";
      c->relay_on = 0;
    }
  }
#endif
  if (error) {
    ++c->bad_configs;
    fprintf(stderr, "pidlab-controller-c: ignoring configuration of episode %lld: %s\n",
            (long long)m->episode_id, error);
    return;
  }
  c->episode_id = m->episode_id;
  c->have_episode = 1;
  c->total_steps = m->total_steps;
  c->reference = m->reference;
  c->expected = 0;
  c->have_last = 0;
  c->relay_printed = 0;
  ++c->episodes;
  if (c->print_configs) print_config(m);
  ack(c, c->episode_id);
}

static void on_ready(const lcm_recv_buf_t *rbuf, const char *ch, const pidlab_lcmt_ready *m, void *user) {
  (void)rbuf;
  (void)ch;
  if (m->state == PIDLAB_LCMT_READY_PING) ack((controller *)user, 0);
}

static void publish_last(controller *c) {
  char name[96];
  channel(c, "CONTROL", name, sizeof name);
  c->last.utime = now_utime();
  pidlab_lcmt_control_command_publish(c->lcm[kControlLane], name, &c->last);
}

static void on_output(const lcm_recv_buf_t *rbuf, const char *ch, const pidlab_lcmt_plant_output *m,
                      void *user) {
  controller *c = (controller *)user;
  (void)rbuf;
  (void)ch;
  if (!c->have_episode || m->episode_id != c->episode_id) {
    ++c->foreign;
    return;
  }
  if (m->step == c->expected && m->step < c->total_steps) {
    double u = 0.0; /* INVALID_INPUT: the C++ sends the 0.0 its u was initialised with */
    pidlab_pid_status status = PIDLAB_PID_INVALID_INPUT;
#ifdef PIDLAB_Q_BITS
    pidlab_q uq = 0;
    if (!c->relay_on && finite(m->y)) {
      status = pidlab_pid_step(&c->pid, to_q_in(c->reference), to_q_in(m->y), &uq);
      u = from_q_out(uq);
    }
#else
    if (!c->relay_on) { /* double or float: the module's pidlab_real */
      pidlab_real ur = 0;
      status = pidlab_pid_step(&c->pid, (pidlab_real)c->reference, (pidlab_real)m->y, &ur);
      u = (double)ur;
    }
#endif
#ifdef PIDLAB_RELAY
    else if (c->relay_on && finite(m->y)) { /* the relay: its u, status OK, as pidlab-controller's */
#ifdef PIDLAB_Q_BITS
      u = from_q_out(pidlab_relay_step(&c->relay, to_q_in(c->reference), to_q_in(m->y)));
#else
      u = pidlab_relay_step(&c->relay, m->t_s, c->reference, m->y);
#endif
      status = PIDLAB_PID_OK;
      if (c->print_relay && !c->relay_printed && pidlab_relay_get_phase(&c->relay) >= PIDLAB_RELAY_DONE) {
        print_relay_end(c);
        c->relay_printed = 1;
      }
    }
#endif
    c->last.episode_id = c->episode_id;
    c->last.step = m->step;
    c->last.t_s = m->t_s;
    c->last.r = c->reference;
    c->last.y = m->y;
    c->last.u = u;
    c->last.status = status == PIDLAB_PID_OK          ? PIDLAB_LCMT_CONTROL_COMMAND_OK
                     : status == PIDLAB_PID_SATURATED ? PIDLAB_LCMT_CONTROL_COMMAND_SATURATED
                                                      : PIDLAB_LCMT_CONTROL_COMMAND_INVALID_INPUT;
    c->have_last = 1;
    ++c->expected;
    ++c->commands;
    publish_last(c);
    if (m->step + 1 == c->total_steps)
      fprintf(stderr, "pidlab-controller-c: episode %lld: done, %lld commands\n", (long long)c->episode_id,
              (long long)c->expected);
  } else if (c->have_last && m->step == c->last.step) {
    if (memcmp(&m->y, &c->last.y, sizeof m->y) != 0)
      ++c->conflicts; /* a different y for a step already answered: repeat, never compute */
    else
      ++c->duplicates; /* the plant did not hear us */
    publish_last(c);
  } else {
    ++c->duplicates;
  }
}

/* udpm://GROUP[:PORT][?QUERY] with the port moved by `lane`. */
static int lane_url(const char *url, int lane, char *out, size_t size) {
  const char *host = url + 7, *query = strchr(host, '?'), *colon;
  char address[128];
  size_t n = query ? (size_t)(query - host) : strlen(host);
  long port = 7667;
  if (strncmp(url, "udpm://", 7) != 0 || n == 0 || n >= sizeof address) return 0;
  memcpy(address, host, n);
  address[n] = '\0';
  colon = strrchr(address, ':');
  if (colon) {
    char *end;
    port = strtol(colon + 1, &end, 10);
    if (*end != '\0' || port < 1 || port > 65535 - kControlLane) return 0;
    address[colon - address] = '\0';
  }
  return snprintf(out, size, "udpm://%s:%ld%s", address, port + lane, query ? query : "") < (int)size;
}

int main(int argc, char **argv) {
  static controller c;
  const char *url = getenv("PIDLAB_LCM_URL"), *prefix = getenv("PIDLAB_CHANNEL_PREFIX");
  int verbose = 0, i, lane;
  char name[96];
  if (!url || !*url) url = "udpm://239.255.76.67:7667?ttl=0";
  if (!prefix || !*prefix) prefix = "PIDLAB_";
  for (i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--lcm-url") && i + 1 < argc)
      url = argv[++i];
    else if (!strcmp(argv[i], "--channel-prefix") && i + 1 < argc)
      prefix = argv[++i];
    else if (!strcmp(argv[i], "--verbose") || !strcmp(argv[i], "-v"))
      verbose = 1;
    else if (!strcmp(argv[i], "--print-configs"))
      c.print_configs = 1;
    else if (!strcmp(argv[i], "--print-relay"))
      c.print_relay = 1;
    else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      printf(
          "pidlab-controller-c: the trio's controller role in C (docs/export.md)\n"
          "usage: pidlab-controller-c [--lcm-url URL] [--channel-prefix P] [--verbose] [--print-configs]\n"
          "                           [--print-relay]\n"
          "  --lcm-url URL       udpm://GROUP:PORT?ttl=N (default $PIDLAB_LCM_URL, else "
          "udpm://239.255.76.67:7667?ttl=0)\n"
          "  --channel-prefix P  prefix of every channel (default $PIDLAB_CHANNEL_PREFIX, else PIDLAB_)\n"
          "  --verbose, -v       print the counters when stopped\n"
          "  --print-configs     print every configuration accepted, one JSON line of every message field\n"
          "  --print-relay       print each relay episode's end and its cycles, one JSON line\n");
      return 0;
    } else {
      fprintf(stderr, "pidlab-controller-c: error: unknown argument '%.80s'\n", argv[i]);
      return 2;
    }
  }
  if (strlen(prefix) > 44) {
    fprintf(stderr, "pidlab-controller-c: error: channel prefix longer than 44 bytes\n");
    return 2;
  }
  snprintf(c.prefix, sizeof c.prefix, "%s", prefix);
  for (lane = 0; lane < kLanes; ++lane) {
    char lane_address[256];
    if (!lane_url(url, lane, lane_address, sizeof lane_address)) {
      fprintf(stderr, "pidlab-controller-c: error: LCM URL '%.120s' is not udpm://GROUP:PORT\n", url);
      return 2;
    }
    c.lcm[lane] = lcm_create(lane_address);
    if (!c.lcm[lane]) {
      fprintf(stderr, "pidlab-controller-c: failed: cannot start LCM on '%.120s'\n", lane_address);
      return 1;
    }
  }
  channel(&c, "EPISODE_CONFIG", name, sizeof name);
  pidlab_lcmt_episode_config_subscribe(c.lcm[0], name, on_config, &c);
  channel(&c, "READY", name, sizeof name);
  pidlab_lcmt_ready_subscribe(c.lcm[0], name, on_ready, &c);
  channel(&c, "PLANT_OUTPUT", name, sizeof name);
  pidlab_lcmt_plant_output_subscribe(c.lcm[kPlantOutputLane], name, on_output, &c);
  signal(SIGTERM, on_signal);
  signal(SIGINT, on_signal);
  while (!stop) {
    fd_set fds;
    struct timeval timeout = {0, 50000};
    int top = 0;
    FD_ZERO(&fds);
    for (lane = 0; lane < 2; ++lane) {
      const int fd = lcm_get_fileno(c.lcm[lane]);
      FD_SET(fd, &fds);
      if (fd > top) top = fd;
    }
    if (select(top + 1, &fds, NULL, NULL, &timeout) > 0)
      for (lane = 0; lane < 2; ++lane)
        if (FD_ISSET(lcm_get_fileno(c.lcm[lane]), &fds)) lcm_handle(c.lcm[lane]);
  }
  if (verbose)
    fprintf(stderr,
            "pidlab-controller-c: episodes %ld, commands %ld, foreign %ld, duplicates %ld, bad_configs %ld, "
            "conflicts %ld\n",
            c.episodes, c.commands, c.foreign, c.duplicates, c.bad_configs, c.conflicts);
  for (lane = 0; lane < kLanes; ++lane) lcm_destroy(c.lcm[lane]);
  return 0;
}
