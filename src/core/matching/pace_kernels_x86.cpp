// The AVX2 and AVX-512BW kernels of PaceMatcher (x86 only; on other architectures this file compiles to
// nothing). Each function carries GCC's target attribute, so the library builds for any x86-64 and
// pace_kernels.cpp picks a kernel the running CPU supports. They compute exactly what chunkPortable computes:
// 16 (AVX2) or 32 (AVX-512) places a vector, one 16-bit lane a place, the same rounding and saturation.
#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include "pace_kernels.h"

// GCC 12's AVX-512 headers start vectors from _mm512_undefined_*, which -Wmaybe-uninitialized reports in every
// caller (a false positive, as in hamming_avx512.cpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace openable
{
namespace pace_kernels
{
namespace
{
// ---------------------------------------------------------------------------------------------- AVX-512BW
template <bool kMasked>
__attribute__((target("avx512f,avx512bw"))) inline __m512i load512(__mmask32 mask, const int16_t* p)
{
  return kMasked ? _mm512_maskz_loadu_epi16(mask, p) : _mm512_loadu_si512(p);
}

template <bool kMasked>
__attribute__((target("avx512f,avx512bw"))) inline void store512(__mmask32 mask, int16_t* p, __m512i x)
{
  if (kMasked)
    _mm512_mask_storeu_epi16(p, mask, x);
  else
    _mm512_storeu_si512(p, x);
}

/// Entry terms of 16 places: vcvtdq2ps, vmulps, vminps, vcvtps2dq (round to nearest even), vpmovdw.
__attribute__((target("avx512f,avx512bw"))) inline __m256i entries512(__m512i r, __m512 scale)
{
  const __m512 x = _mm512_min_ps(_mm512_mul_ps(_mm512_cvtepi32_ps(r), scale), _mm512_set1_ps(float(kOne)));
  return _mm512_cvtepi32_epi16(_mm512_cvtps_epi32(x));
}

/// One pace's costs for the 32 places from i (fewer under a mask) from the previous costs of the places it comes
/// from (`old`), of the places one off its line (`off`, used when kSlip), the smallest cost of each place so far and,
/// when `with_prior` is not null, the smallest cost plus its pace's prior.
template <bool kMasked, bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline void pace512(__m512i old, __m512i off, int16_t* to,
                                                                const int16_t* with_change, const int16_t* entry,
                                                                int16_t* best, size_t i, __mmask32 mask, __m512i keep,
                                                                __m512i slip, uint16_t* with_prior, __m512i prior)
{
  __m512i path = _mm512_min_epi16(old, load512<kMasked>(mask, with_change + i));
  if (kSlip)
    path = _mm512_min_epi16(path, _mm512_adds_epi16(off, slip));
  const __m512i cost = _mm512_adds_epi16(load512<kMasked>(mask, entry + i), _mm512_mulhrs_epi16(path, keep));
  store512<kMasked>(mask, to + i, cost);
  store512<kMasked>(mask, best + i, _mm512_min_epi16(load512<kMasked>(mask, best + i), cost));
  if (with_prior)
  {
    int16_t* lanes = reinterpret_cast<int16_t*>(with_prior) + i;
    store512<kMasked>(mask, lanes, _mm512_min_epu16(load512<kMasked>(mask, lanes), _mm512_adds_epu16(cost, prior)));
  }
}

/// The index vector that picks (before, now)[32 + k - behind] for lane k: indices 0..31 pick `before`, 32..63 `now`.
__attribute__((target("avx512f,avx512bw"))) inline __m512i behindIndex(long behind)
{
  return _mm512_add_epi16(_mm512_set_epi16(31, 30, 29, 28, 27, 26, 25, 24, 23, 22, 21, 20, 19, 18, 17, 16, 15, 14, 13,
                                           12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0),
                          _mm512_set1_epi16(static_cast<int16_t>(32 - behind)));
}

/// The previous costs one place off a forward line, from the permutations of the block before and this one: one
/// place further along (`further`) and, where the line advances (`fewer_too`), one fewer. Unused without kSlip.
template <bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline __m512i offLine512(__m512i before, __m512i now, __m512i further,
                                                                      __m512i fewer, bool fewer_too)
{
  if (!kSlip)
    return before;
  const __m512i more = _mm512_permutex2var_epi16(before, further, now);
  return fewer_too ? _mm512_min_epi16(more, _mm512_permutex2var_epi16(before, fewer, now)) : more;
}

/// The same for a reverse line, read from the other buffer: one place further ahead and, where the line advances,
/// one fewer.
template <bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline __m512i offLineReverse512(const int16_t* from, __mmask32 mask,
                                                                             size_t i, bool fewer_too)
{
  if (!kSlip)
    return _mm512_setzero_si512();
  const __m512i more = _mm512_maskz_loadu_epi16(mask, from + i + 1);
  return fewer_too ? _mm512_min_epi16(more, _mm512_maskz_loadu_epi16(mask, from + i - 1)) : more;
}

/// A forward pace over the chunk, updated in place in the order of memory: each block's previous costs are kept
/// in a register before they are overwritten, and the places `step` behind (and, with kSlip, step + 1 and step - 1
/// behind) are permutations of that block and the next (the first block's come from the segment's padding).
template <bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline void forward512(int16_t* row, long step, const int16_t* with_change,
                                                                   const int16_t* entry, int16_t* best, size_t whole,
                                                                   __mmask32 top, __m512i keep, __m512i slip,
                                                                   uint16_t* with_prior, __m512i prior)
{
  const __m512i index = behindIndex(step), further = behindIndex(step + 1),
                fewer = behindIndex(step > 0 ? step - 1 : 0);
  // Only the last places of the block before the chunk are used: the padding, nothing before it is read.
  const long used = kSlip ? step + 1 : step;
  const __mmask32 padding = used > 0 ? __mmask32(~0u << (32 - used)) : __mmask32(0);
  __m512i before = _mm512_maskz_loadu_epi16(padding, row - 32);
  for (size_t i = 0; i < whole; i += 32)
  {
    const __m512i now = _mm512_loadu_si512(row + i);
    pace512<false, kSlip>(_mm512_permutex2var_epi16(before, index, now),
                          offLine512<kSlip>(before, now, further, fewer, step > 0), row, with_change, entry, best, i,
                          ~__mmask32(0), keep, slip, with_prior, prior);
    before = now;
  }
  if (top)
  {
    const __m512i now = _mm512_maskz_loadu_epi16(top, row + whole);
    pace512<true, kSlip>(_mm512_permutex2var_epi16(before, index, now),
                         offLine512<kSlip>(before, now, further, fewer, step > 0), row, with_change, entry, best, whole,
                         top, keep, slip, with_prior, prior);
  }
}

/// A reverse pace over the chunk: the previous costs are in another buffer, read at or ahead of the place (and one
/// place either side of that, with kSlip: one further, and one fewer where the line advances).
template <bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline void reverse512(const PaceRow& row, const int16_t* with_change,
                                                                   const int16_t* entry, int16_t* best, size_t whole,
                                                                   __mmask32 top, __m512i keep, __m512i slip,
                                                                   uint16_t* with_prior, __m512i prior)
{
  const int16_t* from = row.from + row.offset;
  for (size_t i = 0; i < whole; i += 32)
    pace512<false, kSlip>(_mm512_loadu_si512(from + i),
                          offLineReverse512<kSlip>(from, ~__mmask32(0), i, row.offset != 0), row.to, with_change, entry,
                          best, i, ~__mmask32(0), keep, slip, with_prior, prior);
  if (top)
    pace512<true, kSlip>(_mm512_maskz_loadu_epi16(top, from + whole),
                         offLineReverse512<kSlip>(from, top, whole, row.offset != 0), row.to, with_change, entry, best,
                         whole, top, keep, slip, with_prior, prior);
}

/// Every pace of the chunk, forward in place or reverse from the other buffer (kSlip: with the slip term).
template <bool kSlip>
__attribute__((target("avx512f,avx512bw"))) inline void paces512(const Chunk& c, int16_t* best, size_t whole,
                                                                 __mmask32 top, __m512i keep, uint16_t* searched)
{
  for (size_t v = 0; v < c.paces; ++v)
  {
    const PaceRow& row = c.rows[v];
    const __m512i slip = _mm512_set1_epi16(kSlip ? row.slip : 0);
    const __m512i prior = _mm512_set1_epi16(static_cast<int16_t>(c.prior ? c.prior[v] : 0));
    const int16_t* with_change = c.with_change + c.slot[v] * c.stride;
    if (row.from == row.to)
      forward512<kSlip>(row.to, -row.offset, with_change, c.entry, best, whole, top, keep, slip, searched, prior);
    else
      reverse512<kSlip>(row, with_change, c.entry, best, whole, top, keep, slip, searched, prior);
  }
}

// ---------------------------------------------------------------------------------------------- AVX2
/// Entry terms of 8 places, as entries512.
__attribute__((target("avx2"))) inline __m128i entries256(__m256i r, __m256 scale)
{
  const __m256 x = _mm256_min_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(r), scale), _mm256_set1_ps(float(kOne)));
  const __m256i e = _mm256_cvtps_epi32(x);
  return _mm_packs_epi32(_mm256_castsi256_si128(e), _mm256_extracti128_si256(e, 1));  // 0..32767: no saturation
}

__attribute__((target("avx2"))) inline __m256i load256(const int16_t* p)
{
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

/// One pace's costs for the 16 places from i; with kSlip, also from the places one off its line: `further` (-1
/// forward, +1 reverse) and, when `fewer`, the other side; with `with_prior`, the smallest cost plus prior as pace512.
template <bool kSlip>
__attribute__((target("avx2"))) inline void pace256(const int16_t* from, int16_t* to, const int16_t* with_change,
                                                    const int16_t* entry, int16_t* best, size_t i, __m256i keep,
                                                    long further, bool fewer, __m256i slip, uint16_t* with_prior,
                                                    __m256i prior)
{
  __m256i path = _mm256_min_epi16(load256(from + i), load256(with_change + i));
  if (kSlip)
  {
    __m256i off = load256(from + i + further);
    if (fewer)
      off = _mm256_min_epi16(off, load256(from + i - further));
    path = _mm256_min_epi16(path, _mm256_adds_epi16(off, slip));
  }
  const __m256i cost = _mm256_adds_epi16(load256(entry + i), _mm256_mulhrs_epi16(path, keep));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(to + i), cost);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(best + i), _mm256_min_epi16(load256(best + i), cost));
  if (with_prior)
  {
    auto* lanes = reinterpret_cast<__m256i*>(with_prior + i);
    _mm256_storeu_si256(lanes, _mm256_min_epu16(_mm256_loadu_si256(lanes), _mm256_adds_epu16(cost, prior)));
  }
}

/// Every pace over the chunk's whole blocks of 16, from the top block down (kSlip: with the slip term). Forward rows
/// are updated in place, so the places one off the line (at most the block itself) are still the previous frame's.
template <bool kSlip>
__attribute__((target("avx2"))) inline void paces256(const Chunk& c, int16_t* best, size_t whole, __m256i keep,
                                                     uint16_t* searched)
{
  for (size_t v = 0; v < c.paces; ++v)
  {
    const PaceRow& row = c.rows[v];
    const __m256i slip = _mm256_set1_epi16(kSlip ? row.slip : 0);
    const __m256i prior = _mm256_set1_epi16(static_cast<int16_t>(c.prior ? c.prior[v] : 0));
    const int16_t* from = row.from + row.offset;
    const int16_t* with_change = c.with_change + c.slot[v] * c.stride;
    const long further = row.from == row.to ? -1 : 1;
    const bool fewer = row.offset != 0;
    for (size_t k = whole; k > 0;)
    {
      k -= 16;
      pace256<kSlip>(from, row.to, with_change, c.entry, best, k, keep, further, fewer, slip, searched, prior);
    }
  }
}
}  // namespace

__attribute__((target("avx512f,avx512bw"))) ChunkSums chunkAvx512(const Chunk& c)
{
  ChunkSums sums;
  // Entry terms, 16 places a vector; lanes past the chunk load as 0 and are not stored.
  const uint32_t* own = c.raw + c.tolerance;
  const __m512 scale = _mm512_set1_ps(c.entry_scale);
  for (size_t i = 0; i < c.m; i += 16)
  {
    const __mmask16 mask = c.m - i >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << (c.m - i)) - 1);
    const __m512i r = _mm512_maskz_loadu_epi32(mask, own + i);
    __m512i nearest = r;
    for (long k = 1; k <= c.tolerance; ++k)
      nearest = _mm512_min_epu32(nearest, _mm512_min_epu32(_mm512_maskz_loadu_epi32(mask, own + i - k),
                                                           _mm512_maskz_loadu_epi32(mask, own + i + k)));
    const __m256i entry = entries512(nearest, scale);
    const __m256i extra = _mm256_sub_epi16(entries512(r, scale), entry);
    _mm512_mask_storeu_epi16(c.entry + i, __mmask32(mask), _mm512_castsi256_si512(entry));
    _mm512_mask_storeu_epi16(c.extra + i, __mmask32(mask), _mm512_castsi256_si512(extra));
  }
  // M' + change once per offset (several paces advance the same places this frame), then pace by pace over
  // the chunk (one run of 64-byte lines of each row), in the order of memory.
  const size_t m = c.m, whole = m - m % 32;
  const __mmask32 top = __mmask32((1u << (m - whole)) - 1);
  const __m512i change = _mm512_set1_epi16(c.change), keep = _mm512_set1_epi16(c.keep);
  const __m512i highest = _mm512_set1_epi16(static_cast<int16_t>(kOne));
  for (size_t u = 0; u < c.distinct; ++u)
  {
    const int16_t* old_best = c.old_best + static_cast<long>(c.begin) + c.offsets[u];
    int16_t* with_change = c.with_change + u * c.stride;
    for (size_t i = 0; i < whole; i += 32)
      _mm512_storeu_si512(with_change + i, _mm512_adds_epi16(_mm512_loadu_si512(old_best + i), change));
    if (top)
      _mm512_mask_storeu_epi16(with_change + whole, top,
                               _mm512_adds_epi16(_mm512_maskz_loadu_epi16(top, old_best + whole), change));
  }
  int16_t* best = c.smallest;
  for (size_t i = 0; i < m; i += 32)
    _mm512_storeu_si512(best + i, highest);
  uint16_t* searched = searchedOf(c);
  if (searched)
    for (size_t i = 0; i < m; i += 32)
      _mm512_mask_storeu_epi16(searched + i, i < whole ? ~__mmask32(0) : top, _mm512_set1_epi16(-1));
  if (c.slips)
    paces512<true>(c, best, whole, top, keep, searched);
  else
    paces512<false>(c, best, whole, top, keep, searched);
  __m512i minimum = highest;
  const __m512i unsigned_highest = _mm512_set1_epi16(-1);
  __m512i searched_minimum = unsigned_highest;
  int16_t* out = c.best + c.begin;
  for (size_t i = 0; i < m; i += 32)
  {
    const __mmask32 mask = i < whole ? ~__mmask32(0) : top;
    const __m512i extra = _mm512_maskz_loadu_epi16(mask, c.extra + i);
    const __m512i value = _mm512_adds_epi16(_mm512_maskz_loadu_epi16(mask, best + i), extra);
    _mm512_mask_storeu_epi16(out + i, mask, value);
    minimum = _mm512_min_epi16(minimum, _mm512_mask_blend_epi16(mask, highest, value));
    if (searched)
    {
      int16_t* lanes = reinterpret_cast<int16_t*>(searched) + i;
      const __m512i cost = _mm512_adds_epu16(_mm512_maskz_loadu_epi16(mask, lanes), extra);
      _mm512_mask_storeu_epi16(lanes, mask, cost);
      searched_minimum = _mm512_min_epu16(searched_minimum, _mm512_mask_blend_epi16(mask, unsigned_highest, cost));
    }
  }
  const __m512i low = _mm512_cvtepi16_epi32(_mm512_castsi512_si256(minimum));
  const __m512i high = _mm512_cvtepi16_epi32(_mm512_extracti64x4_epi64(minimum, 1));
  sums.minimum = static_cast<int16_t>(_mm512_reduce_min_epi32(_mm512_min_epi32(low, high)));
  if (searched)
  {
    const __m512i low_searched = _mm512_cvtepu16_epi32(_mm512_castsi512_si256(searched_minimum));
    const __m512i high_searched = _mm512_cvtepu16_epi32(_mm512_extracti64x4_epi64(searched_minimum, 1));
    sums.searched_minimum =
        static_cast<uint16_t>(_mm512_reduce_min_epu32(_mm512_min_epu32(low_searched, high_searched)));
  }
  return sums;
}

__attribute__((target("avx2"))) ChunkSums chunkAvx2(const Chunk& c)
{
  ChunkSums sums;
  const uint32_t* own = c.raw + c.tolerance;
  const __m256 scale = _mm256_set1_ps(c.entry_scale);
  size_t i = 0;
  for (; i + 8 <= c.m; i += 8)
  {
    const __m256i r = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(own + i));
    __m256i nearest = r;
    for (long k = 1; k <= c.tolerance; ++k)
      nearest = _mm256_min_epu32(nearest,
                                 _mm256_min_epu32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(own + i - k)),
                                                  _mm256_loadu_si256(reinterpret_cast<const __m256i*>(own + i + k))));
    const __m128i entry = entries256(nearest, scale);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(c.entry + i), entry);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(c.extra + i), _mm_sub_epi16(entries256(r, scale), entry));
  }
  for (; i < c.m; ++i)
    prepare(c, i);
  // The partial block at the top place by place, then pace by pace over the whole blocks of 16, downwards.
  const size_t whole = c.m - c.m % 16;
  for (size_t k = c.m; k-- > whole;)
    update(c, k, sums);
  const __m256i change = _mm256_set1_epi16(c.change), keep = _mm256_set1_epi16(c.keep);
  const __m256i highest = _mm256_set1_epi16(static_cast<int16_t>(kOne));
  for (size_t u = 0; u < c.distinct; ++u)
  {
    const int16_t* old_best = c.old_best + static_cast<long>(c.begin) + c.offsets[u];
    int16_t* with_change = c.with_change + u * c.stride;
    for (size_t k = 0; k < whole; k += 16)
      _mm256_storeu_si256(
          reinterpret_cast<__m256i*>(with_change + k),
          _mm256_adds_epi16(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(old_best + k)), change));
  }
  int16_t* best = c.smallest;
  for (size_t k = 0; k < whole; k += 16)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(best + k), highest);
  uint16_t* searched = searchedOf(c);
  if (searched)
    std::fill_n(searched, whole, UINT16_MAX);
  if (c.slips)
    paces256<true>(c, best, whole, keep, searched);
  else
    paces256<false>(c, best, whole, keep, searched);
  __m256i minimum = highest, searched_minimum = _mm256_set1_epi16(-1);
  int16_t* out = c.best + c.begin;
  for (size_t k = 0; k < whole; k += 16)
  {
    const __m256i extra = load256(c.extra + k);
    const __m256i value = _mm256_adds_epi16(load256(best + k), extra);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + k), value);
    minimum = _mm256_min_epi16(minimum, value);
    if (searched)
    {
      auto* lanes = reinterpret_cast<__m256i*>(searched + k);
      const __m256i cost = _mm256_adds_epu16(_mm256_loadu_si256(lanes), extra);
      _mm256_storeu_si256(lanes, cost);
      searched_minimum = _mm256_min_epu16(searched_minimum, cost);
    }
  }
  alignas(32) int16_t values[16];
  _mm256_store_si256(reinterpret_cast<__m256i*>(values), minimum);
  for (int16_t x : values)
    sums.minimum = std::min(sums.minimum, x);
  alignas(32) uint16_t minima[16];
  _mm256_store_si256(reinterpret_cast<__m256i*>(minima), searched_minimum);
  for (uint16_t x : minima)
    sums.searched_minimum = std::min(sums.searched_minimum, x);
  return sums;
}

}  // namespace pace_kernels
}  // namespace openable

#pragma GCC diagnostic pop

#endif  // x86
