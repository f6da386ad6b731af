/* pidlab PIL firmware: the exported controller (pidlab_pid.c, any scalar)
 * served over UART0 of QEMU's MPS2 boards (pil_protocol.h). Each PIL_STEP is
 * one pidlab_pid_step, timed by SysTick: with QEMU's -icount shift=0 one
 * instruction is one nanosecond of virtual time and SysTick counts the
 * board's 25 MHz, so a tick is 40 instructions (docs/pil.md). */
#include <stdint.h>
#include <string.h>

#include "pidlab_pid.h"
#include "pil_protocol.h"

#define UART0 0x40004000u
#define UART_DATA (*(volatile uint32_t *)(UART0 + 0x00u))
#define UART_STATE (*(volatile uint32_t *)(UART0 + 0x04u))
#define UART_CTRL (*(volatile uint32_t *)(UART0 + 0x08u))
#define UART_BAUDDIV (*(volatile uint32_t *)(UART0 + 0x10u))
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

extern uint32_t _sstack, _estack;
void pil_main(void);

static pidlab_pid pid;

static uint8_t get_byte(void) {
  while (!(UART_STATE & 2u)) {
  }
  return (uint8_t)UART_DATA;
}

static void put_byte(uint8_t b) {
  while (UART_STATE & 1u) {
  }
  UART_DATA = b;
}

static void send(uint8_t type, const uint8_t *payload, uint8_t n) {
  uint8_t head[2];
  uint16_t crc;
  unsigned i;
  head[0] = type;
  head[1] = n;
  crc = pil_crc16(payload, n, pil_crc16(head, 2, 0xFFFFu));
  put_byte(PIL_SYNC0);
  put_byte(PIL_SYNC1);
  put_byte(type);
  put_byte(n);
  for (i = 0; i < n; ++i) put_byte(payload[i]);
  put_byte((uint8_t)(crc & 0xFFu));
  put_byte((uint8_t)(crc >> 8));
}

static void error(uint8_t code) { send(PIL_ERROR, &code, 1); }

static double get_double(const uint8_t *p) {
  double v;
  memcpy(&v, p, sizeof v);
  return v;
}

static void configure(const uint8_t *p) {
  pidlab_pid_config c;
  int32_t status;
  memset(&c, 0, sizeof c);
  c.kp = get_double(p + 0);
  c.ki = get_double(p + 8);
  c.kd = get_double(p + 16);
  c.tf = get_double(p + 24);
  c.setpoint_weight_b = get_double(p + 32);
  c.setpoint_weight_c = get_double(p + 40);
  c.dt_s = get_double(p + 48);
  c.output_min = get_double(p + 56);
  c.output_max = get_double(p + 64);
#ifndef PIDLAB_Q_BITS
  c.has_output_min = get_double(p + 72) != 0.0;
  c.has_output_max = get_double(p + 80) != 0.0;
#endif
  c.anti_windup = (pidlab_anti_windup)(int)get_double(p + 88);
  c.back_calculation_gain = get_double(p + 96);
  c.integral = (pidlab_integral_rule)(int)get_double(p + 104);
  c.setpoint_filter_s = get_double(p + 112);
  status = (int32_t)pidlab_pid_init(&pid, &c);
  send(PIL_ACK, (const uint8_t *)&status, 4);
}

#ifdef PIL_FAULT
/* Test builds only (PIDLAB_PIL_CFLAGS="-DPIL_FAULT=1|2 -DPIL_FAULT_STEP=N"):
 * at step N, 1 sends a wrong frame, 2 stalls. */
static unsigned long pil_steps;
#endif

static void step(const uint8_t *p) {
  uint8_t out[13];
  uint32_t t0, t1;
  pidlab_pid_status status;
#ifdef PIL_FAULT
  if (++pil_steps == PIL_FAULT_STEP) {
#if PIL_FAULT == 1
    put_byte(0x00);
    put_byte(0x13);
#else
    for (;;) {
    }
#endif
  }
#endif
#ifdef PIDLAB_Q_BITS
  int64_t r64, y64, u64;
  pidlab_q r, y, u = 0;
  memcpy(&r64, p, 8);
  memcpy(&y64, p + 8, 8);
  r = (pidlab_q)r64;
  y = (pidlab_q)y64;
#else
  pidlab_real r = (pidlab_real)get_double(p), y = (pidlab_real)get_double(p + 8), u = 0;
  double u64;
#endif
  t0 = SYST_CVR;
  status = pidlab_pid_step(&pid, r, y, &u);
  t1 = SYST_CVR;
#ifdef PIDLAB_Q_BITS
  u64 = (int64_t)u;
#else
  u64 = (double)u;
#endif
  memcpy(out, &u64, 8);
  out[8] = (uint8_t)status;
  t0 = (t0 - t1) & 0xFFFFFFu;
  memcpy(out + 9, &t0, 4);
  send(PIL_U, out, 13);
}

static void stats(void) {
  uint32_t out[2];
  const uint32_t *p = &_sstack;
  while (p < &_estack && *p == 0xA5A5A5A5u) ++p;
  out[0] = (uint32_t)((const uint8_t *)&_estack - (const uint8_t *)p);
  out[1] = (uint32_t)((const uint8_t *)&_estack - (const uint8_t *)&_sstack);
  send(PIL_STATS_REPLY, (const uint8_t *)out, 8);
}

void pil_main(void) {
  static uint8_t buf[256];
  UART_BAUDDIV = 16u;
  UART_CTRL = 3u; /* TX and RX enabled */
  SYST_RVR = 0xFFFFFFu;
  SYST_CVR = 0u;
  SYST_CSR = 5u; /* enabled, processor clock, no interrupt */
  for (;;) {
    uint8_t head[2], n, type;
    uint16_t crc;
    unsigned i;
    if (get_byte() != PIL_SYNC0) continue;
    if (get_byte() != PIL_SYNC1) continue;
    head[0] = type = get_byte();
    head[1] = n = get_byte();
    for (i = 0; i < n; ++i) buf[i] = get_byte();
    crc = (uint16_t)get_byte();
    crc = (uint16_t)(crc | (uint16_t)(get_byte() << 8));
    if (crc != pil_crc16(buf, n, pil_crc16(head, 2, 0xFFFFu))) {
      error(1);
      continue;
    }
    if (type == PIL_HELLO && n == 0) {
      uint8_t info[28];
      uint32_t v[3];
      double scale[2];
#ifdef PIDLAB_Q_BITS
      v[0] = PIDLAB_Q_BITS == 31 ? 2u : 3u;
      v[2] = PIDLAB_Q_BITS;
      scale[0] = PIDLAB_INPUT_FULL_SCALE;
      scale[1] = PIDLAB_OUTPUT_FULL_SCALE;
#else
      v[0] = sizeof(pidlab_real) == 4 ? 1u : 0u;
      v[2] = 0u;
      scale[0] = scale[1] = 1.0;
#endif
#if defined(__ARM_ARCH_7EM__)
      v[1] = 4u;
#else
      v[1] = 3u;
#endif
      memcpy(info, v, 12);
      memcpy(info + 12, scale, 16);
      send(PIL_INFO, info, 28);
    } else if (type == PIL_CONFIG && n == 120) {
      configure(buf);
    } else if (type == PIL_STEP && n == 16) {
      step(buf);
    } else if (type == PIL_STATS && n == 0) {
      stats();
    } else if (type != PIL_HELLO && type != PIL_CONFIG && type != PIL_STEP && type != PIL_STATS) {
      error(2);
    } else {
      error(3);
    }
  }
}
