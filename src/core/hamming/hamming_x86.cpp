// The POPCNT and AVX2 Hamming kernels (x86 only; on other architectures this file compiles to nothing).
// Each function is compiled for its own instruction set with GCC's target attribute, so the library builds
// for any x86-64 (no -march=native) and hamming.cpp picks the fastest kernel the running CPU supports.
#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include "hamming/hamming_kernels.h"

namespace openable
{
namespace hamming_kernels
{
namespace
{
// ---------------------------------------------------------------------------------------------- popcnt
__attribute__((target("popcnt"))) inline uint32_t pairPopcntInline(const uint64_t* a, const uint64_t* b, size_t words)
{
  uint64_t sum = 0;
  for (size_t i = 0; i < words; ++i)
    sum += static_cast<uint64_t>(_mm_popcnt_u64(a[i] ^ b[i]));
  return static_cast<uint32_t>(sum);
}

__attribute__((target("popcnt"))) uint32_t pairPopcnt(const uint64_t* a, const uint64_t* b, size_t words)
{
  return pairPopcntInline(a, b, words);
}

__attribute__((target("popcnt"))) void rowPopcnt(const uint64_t* q, const uint64_t* rows, size_t stride, size_t words,
                                                 size_t count, uint32_t* out)
{
  for (size_t i = 0; i < count; ++i)
    out[i] = pairPopcntInline(q, rows + i * stride, words);
}

// ---------------------------------------------------------------------------------------------- AVX2
// Bit count of every byte by two 4-bit table lookups (vpshufb), summed per 64-bit lane with vpsadbw.
__attribute__((target("avx2,popcnt"))) inline uint32_t pairAvx2Inline(const uint64_t* a, const uint64_t* b,
                                                                      size_t words)
{
  const __m256i table =
      _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low_mask = _mm256_set1_epi8(0x0f);
  __m256i total = _mm256_setzero_si256();
  size_t i = 0;
  for (; i + 4 <= words; i += 4)
  {
    const __m256i x = _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + i)),
                                       _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + i)));
    const __m256i lo = _mm256_shuffle_epi8(table, _mm256_and_si256(x, low_mask));
    const __m256i hi = _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(x, 4), low_mask));
    total = _mm256_add_epi64(total, _mm256_sad_epu8(_mm256_add_epi8(lo, hi), _mm256_setzero_si256()));
  }
  uint64_t sum = static_cast<uint64_t>(_mm256_extract_epi64(total, 0)) + _mm256_extract_epi64(total, 1) +
                 _mm256_extract_epi64(total, 2) + _mm256_extract_epi64(total, 3);
  for (; i < words; ++i)
    sum += static_cast<uint64_t>(_mm_popcnt_u64(a[i] ^ b[i]));
  return static_cast<uint32_t>(sum);
}

__attribute__((target("avx2,popcnt"))) uint32_t pairAvx2(const uint64_t* a, const uint64_t* b, size_t words)
{
  return pairAvx2Inline(a, b, words);
}

__attribute__((target("avx2,popcnt"))) void rowAvx2(const uint64_t* q, const uint64_t* rows, size_t stride,
                                                    size_t words, size_t count, uint32_t* out)
{
  for (size_t i = 0; i < count; ++i)
    out[i] = pairAvx2Inline(q, rows + i * stride, words);
}
}  // namespace

Kernel popcntKernel()
{
  return kernelOf<pairPopcnt, rowPopcnt>();
}

Kernel avx2Kernel()
{
  return kernelOf<pairAvx2, rowAvx2>();
}

}  // namespace hamming_kernels
}  // namespace openable

#endif  // x86
