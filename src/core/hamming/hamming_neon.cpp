// The NEON Hamming kernel (AArch64 only; on other architectures this file compiles to nothing). Advanced SIMD
// is part of every AArch64 CPU, so no run-time check is needed.
#if defined(__aarch64__)

#include <arm_neon.h>

#include "hamming/hamming_kernels.h"

namespace openable
{
namespace hamming_kernels
{
namespace
{
// Two words a step: vcntq_u8 counts the bits of each of the 16 bytes of their XOR, vpadalq_u8 adds the byte
// counts pairwise into eight 16-bit lanes (at most 16 a step, so 4095 steps fit), widened to 64 bits before
// they could overflow.
inline uint32_t pairNeonInline(const uint64_t* a, const uint64_t* b, size_t words)
{
  constexpr size_t kStepsPerFlush = 4095;
  uint64_t sum = 0;
  size_t i = 0;
  while (i + 2 <= words)
  {
    uint16x8_t counts = vdupq_n_u16(0);
    const size_t end = i + 2 * std::min(kStepsPerFlush, (words - i) / 2);
    for (; i < end; i += 2)
    {
      const uint8x16_t x = veorq_u8(vreinterpretq_u8_u64(vld1q_u64(a + i)), vreinterpretq_u8_u64(vld1q_u64(b + i)));
      counts = vpadalq_u8(counts, vcntq_u8(x));
    }
    sum += vaddlvq_u16(counts);
  }
  if (i < words)
    sum += vaddv_u8(vcnt_u8(vreinterpret_u8_u64(vdup_n_u64(a[i] ^ b[i]))));
  return static_cast<uint32_t>(sum);
}

uint32_t pairNeon(const uint64_t* a, const uint64_t* b, size_t words)
{
  return pairNeonInline(a, b, words);
}

void rowNeon(const uint64_t* q, const uint64_t* rows, size_t stride, size_t words, size_t count, uint32_t* out)
{
  for (size_t i = 0; i < count; ++i)
    out[i] = pairNeonInline(q, rows + i * stride, words);
}
}  // namespace

Kernel neonKernel()
{
  return kernelOf<pairNeon, rowNeon>();
}

}  // namespace hamming_kernels
}  // namespace openable

#endif  // __aarch64__
