/* The PIL link (docs/pil.md): frames between the bridge (pidlab pil) and the
 * firmware over the board's UART0, both ways
 *   0xA5 0x5A TYPE LEN PAYLOAD[LEN] CRC_LO CRC_HI
 * with CRC-16/CCITT-FALSE over TYPE, LEN and the payload. Numbers are little
 * endian; a value slot is 8 bytes: a double, or a pidlab_q sign-extended to
 * int64 (fixed point). */
#ifndef PIDLAB_PIL_PROTOCOL_H_
#define PIDLAB_PIL_PROTOCOL_H_

#include <stdint.h>

#define PIL_SYNC0 0xA5
#define PIL_SYNC1 0x5A
/* bridge -> firmware */
#define PIL_HELLO 'H' /* empty: answered by PIL_INFO */
#define PIL_CONFIG \
  'C' /* 15 doubles: kp ki kd tf b c dt out_min out_max has_min has_max anti_windup aw_gain integral tr */
#define PIL_STEP 'S'  /* r, y: two value slots */
#define PIL_STATS 'T' /* empty: answered by PIL_STATS_REPLY */
/* firmware -> bridge */
#define PIL_INFO \
  'I' /* u32 scalar (0 double, 1 float, 2 q31, 3 q15), u32 core (3, 4), u32 q bits, double X, double U */
#define PIL_ACK 'A'         /* i32 pidlab_pid_status of init */
#define PIL_U 'U'           /* u: one value slot; u8 status; u32 SysTick ticks of the step */
#define PIL_STATS_REPLY 't' /* u32 stack bytes used (painted high-water mark), u32 stack size */
#define PIL_ERROR 'E'       /* u8 code: 1 bad CRC, 2 unknown type, 3 bad length */

static uint16_t pil_crc16(const uint8_t *p, unsigned n, uint16_t crc) {
  unsigned i;
  int b;
  for (i = 0; i < n; ++i) {
    crc ^= (uint16_t)(p[i] << 8);
    for (b = 0; b < 8; ++b)
      crc = (uint16_t)((crc & 0x8000u) ? (unsigned)(crc << 1) ^ 0x1021u : (unsigned)(crc << 1));
  }
  return crc;
}

#endif /* PIDLAB_PIL_PROTOCOL_H_ */
