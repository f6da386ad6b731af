/* pidlab PIL firmware: the vector table and the reset handler (no OS, no
 * libc start files). Copies .data, zeroes .bss, paints the stack with
 * 0xA5A5A5A5 below the current frame, turns the FPU on (Cortex-M4F), calls
 * pil_main. A fault spins: the bridge's deadline names it. */
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _sstack, _estack;
void pil_main(void);
void pil_reset(void);
static void pil_spin(void) {
  for (;;) {
  }
}

__attribute__((section(".vectors"), used)) static void (*const pil_vectors[16])(void) = {
    (void (*)(void))(&_estack),
    pil_reset,
    pil_spin,
    pil_spin,
    pil_spin,
    pil_spin,
    pil_spin,
    0,
    0,
    0,
    0,
    pil_spin,
    pil_spin,
    0,
    pil_spin,
    pil_spin};

void pil_reset(void) {
  uint32_t *s = &_sidata, *d = &_sdata;
  volatile uint32_t *p;
  uint32_t sp;
  while (d < &_edata) *d++ = *s++;
  for (d = &_sbss; d < &_ebss; ++d) *d = 0;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (p = (volatile uint32_t *)&_sstack; (uint32_t)p < sp - 64; ++p) *p = 0xA5A5A5A5u;
#if defined(__ARM_FP)
  *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20; /* CPACR: CP10, CP11 full access */
  __asm__ volatile("dsb\n isb");
#endif
  pil_main();
  pil_spin();
}
