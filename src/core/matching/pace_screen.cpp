// PaceMatcher's screen: one cost a place for every place of a large row (pace_kernels.h ScreenChunk). The portable
// loop, and on x86 AVX2 and AVX-512BW versions chosen at run time; all three compute the same integers.
#include <algorithm>

#include "pace_kernels.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
// GCC 12's AVX-512 headers build some intrinsics on _mm512_undefined_*, which it then reports as uninitialised.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace openable
{
namespace pace_kernels
{
namespace
{
/// Place i of the chunk: its screen cost, and its distance in the sums.
inline void screenPlace(const ScreenChunk& c, size_t i, ScreenSums& sums)
{
  const uint32_t r = c.raw[i];
  sums.sum += r;
  sums.squares += static_cast<uint64_t>(r) * r;
  const long j = static_cast<long>(c.begin + i);
  int32_t path = c.old_screen[j];
  for (long s = 1; s <= c.reach; ++s)
  {
    path = std::min<int32_t>(path, c.old_screen[j - s]);
    if (c.bidirectional)
      path = std::min<int32_t>(path, c.old_screen[j + s]);
  }
  const int16_t cost = addSaturated(entryOf(r, c.entry_scale), scaled(path, c.keep));
  c.screen[j] = cost;
  sums.minimum = std::min(sums.minimum, cost);
}

ScreenSums screenPortable(const ScreenChunk& c)
{
  ScreenSums sums;
  for (size_t i = 0; i < c.m; ++i)
    screenPlace(c, i, sums);
  return sums;
}

#if defined(__x86_64__) || defined(__i386__)
// AVX-512: 32 places at a time in 16-bit lanes. The entry as entryOf (a float product rounded to the nearest, in
// 32-bit lanes, then packed), the smallest of the places a path comes from (vpminsw), the product by a rounded as
// scaled() (vpmulhrsw computes (x a + 2^14) >> 15 exactly), the sum saturated to 16 bits (vpaddsw, as
// addSaturated). The distances' sums in 64-bit lanes, even and odd places apart (no widening shuffle). AVX2: 8 places
// at a time in 32-bit lanes, the same integers.
/// The entries of 16 places in 32-bit lanes, their distances added to the sums.
__attribute__((target("avx512f"))) inline __m512i screenEntries(const uint32_t* raw, __m512 scale, __m512 one,
                                                                __m512i low_half, __m512i& sum, __m512i& squares)
{
  const __m512i r = _mm512_loadu_si512(raw);
  const __m512i odd = _mm512_srli_epi64(r, 32);
  sum = _mm512_add_epi64(sum, _mm512_add_epi64(_mm512_and_si512(r, low_half), odd));
  squares = _mm512_add_epi64(squares, _mm512_add_epi64(_mm512_mul_epu32(r, r), _mm512_mul_epu32(odd, odd)));
  return _mm512_cvtps_epi32(_mm512_min_ps(_mm512_mul_ps(_mm512_cvtepi32_ps(r), scale), one));
}

__attribute__((target("avx512f,avx512bw"))) ScreenSums screenAvx512(const ScreenChunk& c)
{
  ScreenSums sums;
  const __m512 scale = _mm512_set1_ps(c.entry_scale), one = _mm512_set1_ps(float(kOne));
  const __m512i keep = _mm512_set1_epi16(c.keep), low_half = _mm512_set1_epi64(0xffffffff);
  const __m512i in_order = _mm512_set_epi64(7, 5, 3, 1, 6, 4, 2, 0);  // undoes vpackssdw's interleaving of lanes
  __m512i sum = _mm512_setzero_si512(), squares = _mm512_setzero_si512(), minimum = _mm512_set1_epi16(kOne);
  size_t i = 0;
  for (; i + 32 <= c.m; i += 32)
  {
    const __m512i first = screenEntries(c.raw + i, scale, one, low_half, sum, squares);
    const __m512i second = screenEntries(c.raw + i + 16, scale, one, low_half, sum, squares);
    const __m512i entry = _mm512_permutexvar_epi64(in_order, _mm512_packs_epi32(first, second));
    const int16_t* at = c.old_screen + c.begin + i;
    __m512i path = _mm512_loadu_si512(at);
    for (long s = 1; s <= c.reach; ++s)
    {
      path = _mm512_min_epi16(path, _mm512_loadu_si512(at - s));
      if (c.bidirectional)
        path = _mm512_min_epi16(path, _mm512_loadu_si512(at + s));
    }
    const __m512i cost = _mm512_adds_epi16(entry, _mm512_mulhrs_epi16(path, keep));
    minimum = _mm512_min_epi16(minimum, cost);
    _mm512_storeu_si512(c.screen + c.begin + i, cost);
  }
  alignas(64) uint64_t lanes[8];
  _mm512_store_si512(lanes, sum);
  for (uint64_t lane : lanes)
    sums.sum += lane;
  _mm512_store_si512(lanes, squares);
  for (uint64_t lane : lanes)
    sums.squares += lane;
  alignas(64) int16_t smallest[32];
  _mm512_store_si512(smallest, minimum);
  sums.minimum = *std::min_element(smallest, smallest + 32);
  for (; i < c.m; ++i)
    screenPlace(c, i, sums);
  return sums;
}

__attribute__((target("avx2"))) ScreenSums screenAvx2(const ScreenChunk& c)
{
  ScreenSums sums;
  const __m256 scale = _mm256_set1_ps(c.entry_scale), one = _mm256_set1_ps(float(kOne));
  const __m256i keep = _mm256_set1_epi32(c.keep), half = _mm256_set1_epi32(16384), top = _mm256_set1_epi32(32767);
  __m256i sum = _mm256_setzero_si256(), squares = _mm256_setzero_si256(), minimum = _mm256_set1_epi32(kOne);
  size_t i = 0;
  for (; i + 8 <= c.m; i += 8)
  {
    const __m256i r = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.raw + i));
    const __m256i low = _mm256_cvtepu32_epi64(_mm256_castsi256_si128(r));
    const __m256i high = _mm256_cvtepu32_epi64(_mm256_extracti128_si256(r, 1));
    sum = _mm256_add_epi64(sum, _mm256_add_epi64(low, high));
    squares = _mm256_add_epi64(squares, _mm256_add_epi64(_mm256_mul_epu32(low, low), _mm256_mul_epu32(high, high)));
    const __m256i entry = _mm256_cvtps_epi32(_mm256_min_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(r), scale), one));
    const int16_t* at = c.old_screen + c.begin + i;
    __m256i path = _mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at)));
    for (long s = 1; s <= c.reach; ++s)
    {
      path = _mm256_min_epi32(path, _mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at - s))));
      if (c.bidirectional)
        path = _mm256_min_epi32(path, _mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at + s))));
    }
    const __m256i kept = _mm256_srai_epi32(_mm256_add_epi32(_mm256_mullo_epi32(path, keep), half), 15);
    const __m256i cost = _mm256_min_epi32(_mm256_add_epi32(entry, kept), top);
    minimum = _mm256_min_epi32(minimum, cost);
    // Costs are 0..32767: packing the two halves with signed saturation keeps them; the permutation puts them in order.
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packs_epi32(cost, cost), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(c.screen + c.begin + i), _mm256_castsi256_si128(packed));
  }
  alignas(32) uint64_t lanes[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), sum);
  sums.sum = lanes[0] + lanes[1] + lanes[2] + lanes[3];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), squares);
  sums.squares = lanes[0] + lanes[1] + lanes[2] + lanes[3];
  alignas(32) int32_t smallest[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(smallest), minimum);
  sums.minimum = static_cast<int16_t>(*std::min_element(smallest, smallest + 8));
  for (; i < c.m; ++i)
    screenPlace(c, i, sums);
  return sums;
}
#endif

}  // namespace

ScreenFn screenFor(PaceKernel kernel)
{
  requireSupported(kernel);
  switch (kernel)
  {
#if defined(__x86_64__) || defined(__i386__)
    case PaceKernel::kAvx2:
      return screenAvx2;
    case PaceKernel::kAvx512:
      return screenAvx512;
    case PaceKernel::kBest:
      return supported(PaceKernel::kAvx512) ? screenAvx512
             : supported(PaceKernel::kAvx2) ? screenAvx2
                                            : screenPortable;
#endif
    default:
      return screenPortable;
  }
}

}  // namespace pace_kernels
}  // namespace openable

#if defined(__x86_64__) || defined(__i386__)
#pragma GCC diagnostic pop
#endif
