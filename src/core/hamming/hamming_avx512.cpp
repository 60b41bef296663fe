// The AVX-512 VPOPCNTDQ Hamming kernel (x86 only; on other architectures this file compiles to nothing): the
// pair distance, rows of small descriptors eight at a time (VBMI), fused row differences and chain steps.
// Every function carries GCC's target attribute for the instructions it uses, so the library builds for any
// x86-64 and hamming.cpp picks this kernel only on CPUs that support it.
#if defined(__x86_64__) || defined(__i386__)

#include <immintrin.h>

#include <algorithm>
#include <cstring>
#include <new>

#include "hamming/hamming_kernels.h"

namespace openable
{
namespace hamming_kernels
{
namespace
{
// GCC 12's own avx512fintrin.h trips -Wuninitialized inside its reduction helpers (a known false positive).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
__attribute__((target("avx512f,avx512vpopcntdq"))) inline uint32_t pairAvx512Inline(const uint64_t* a,
                                                                                    const uint64_t* b, size_t words)
{
  __m512i total = _mm512_setzero_si512();
  size_t i = 0;
  for (; i + 8 <= words; i += 8)
    total = _mm512_add_epi64(
        total, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_loadu_si512(a + i), _mm512_loadu_si512(b + i))));
  if (i < words)
  {
    // Masked loads read only the remaining words (and never past the end of the descriptor).
    const __mmask8 mask = static_cast<__mmask8>((1u << (words - i)) - 1u);
    const __m512i x = _mm512_xor_si512(_mm512_maskz_loadu_epi64(mask, a + i), _mm512_maskz_loadu_epi64(mask, b + i));
    total = _mm512_add_epi64(total, _mm512_popcnt_epi64(x));
  }
  return static_cast<uint32_t>(_mm512_reduce_add_epi64(total));
}

__attribute__((target("avx512f,avx512vpopcntdq"))) uint32_t pairAvx512(const uint64_t* a, const uint64_t* b,
                                                                       size_t words)
{
  return pairAvx512Inline(a, b, words);
}

// Packed rows of at most 8 words (HOG-B: 6): eight rows are W whole vectors. The per-word bit counts (at most
// 64, a byte) of vector j are shifted into byte j of every 64-bit lane and ORed together; one permutation (VBMI)
// lays each row's W bytes into its own 8-byte group with zeros around them, and one vpsadbw sums every group:
// eight distances with one horizontal step instead of eight reductions. W is a template parameter so that the
// joins are fixed instructions.
template <size_t W>
struct PackedLayout  ///< the constants of PackedRows for rows of W words, computed once
{
  alignas(64) uint64_t lanes[W][8];  ///< lane k of pattern vector j repeats query word (8j + k) mod W
  alignas(64) uint8_t gather[64];    ///< output byte 8r + t takes the count of word W r + t (t < W) ...
  __mmask64 keep = 0;                ///< ... and is zero for t >= W

  PackedLayout()
  {
    for (size_t j = 0; j < W; ++j)
      for (size_t k = 0; k < 8; ++k)
        lanes[j][k] = (8 * j + k) % W;
    for (size_t r = 0; r < 8; ++r)
      for (size_t t = 0; t < 8; ++t)
      {
        const size_t word = W * r + t;  // word 8j + i of the eight rows sits in byte 8i + j of the packed counts
        gather[8 * r + t] = static_cast<uint8_t>(t < W ? 8 * (word % 8) + word / 8 : 0);
        keep |= __mmask64(t < W) << (8 * r + t);
      }
  }
};

template <size_t W>
struct PackedRows
{
  __m512i pattern[W];  ///< the query repeated over eight rows: vector j holds words 8j .. 8j + 7 of that pattern
  __m512i gather;      ///< see PackedLayout
  __mmask64 keep;

  // Built for every block of rows a kernel is called on, so from the constants by one permutation a vector.
  __attribute__((target("avx512f,avx512bw"))) explicit PackedRows(const uint64_t* q)
  {
    static const PackedLayout<W> layout;  // the constants, built once per width
    const __m512i query = _mm512_maskz_loadu_epi64(static_cast<__mmask8>((1u << W) - 1u), q);
    for (size_t j = 0; j < W; ++j)
      pattern[j] = _mm512_permutexvar_epi64(_mm512_load_si512(layout.lanes[j]), query);
    gather = _mm512_load_si512(layout.gather);
    keep = layout.keep;
  }

  /// Bit counts of the eight rows at `r` against the query, one byte per word (see gather).
  __attribute__((target("avx512f,avx512vpopcntdq"))) __m512i counts(const uint64_t* r) const
  {
    __m512i packed = _mm512_setzero_si512();
    for (size_t j = 0; j < W; ++j)
      packed = _mm512_or_si512(
          packed,
          _mm512_slli_epi64(_mm512_popcnt_epi64(_mm512_xor_si512(_mm512_loadu_si512(r + 8 * j), pattern[j])), 8 * j));
    return packed;
  }

  /// The eight 64-bit sums of the bytes of each row (bytes as counts() lays them out).
  __attribute__((target("avx512f,avx512bw,avx512vbmi"))) __m512i wordSums(__m512i bytes) const
  {
    return _mm512_sad_epu8(_mm512_maskz_permutexvar_epi8(keep, gather, bytes), _mm512_setzero_si512());
  }
  /// The same as 32-bit sums.
  __attribute__((target("avx512f,avx512bw,avx512vbmi"))) __m256i sums(__m512i bytes) const
  {
    return _mm512_cvtepi64_epi32(wordSums(bytes));
  }
};

template <size_t W>
__attribute__((target("avx512f,avx512bw,avx512vbmi,avx512vpopcntdq"))) void rowAvx512Packed(const uint64_t* q,
                                                                                            const uint64_t* rows,
                                                                                            size_t count, uint32_t* out)
{
  const PackedRows<W> packed(q);
  size_t i = 0;
  for (; i + 8 <= count; i += 8)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), packed.sums(packed.counts(rows + i * W)));
  for (; i < count; ++i)
    out[i] = pairAvx512Inline(q, rows + i * W, W);
}

// The nearest of several queries to each row (a frame and its views shifted sideways): every block of eight rows
// is loaded once and its distances to each query, eight 64-bit sums, are reduced by one vpminuq a query, so the
// views cost their popcounts, not a row of distances stored and read back. At most kMostNearestQueries queries
// (their patterns stay in registers); PackedRows holds only vectors, so nothing needs destroying.
constexpr size_t kMostNearestQueries = 4;
// PaceMatcher calls this a chunk of 2048 places at a time, with the screen and the refined paces' costs between two
// chunks: the rows 4 KB on are prefetched, so the next chunk's first rows are on their way while those run, where the
// hardware's prefetcher would start again at each chunk. Two channels at 1e6 places, twelve runs each, in turn with
// and without: 3.89 / 4.03 ms against 4.13 / 4.74 (minimum / median); 2 and 8 KB measured the same as 4. A prefetch
// past the end of the map reads nothing and never faults.
constexpr size_t kPrefetchWords = 512;

template <size_t W>
__attribute__((target("avx512f,avx512bw,avx512vbmi,avx512vpopcntdq"))) void rowNearestAvx512Packed(
    const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t count, uint32_t* out)
{
  alignas(PackedRows<W>) unsigned char storage[kMostNearestQueries][sizeof(PackedRows<W>)];
  const PackedRows<W>* packed[kMostNearestQueries];
  for (size_t q = 0; q < nq; ++q)
    packed[q] = new (storage[q]) PackedRows<W>(queries[q]);
  size_t i = 0;
  for (; i + 8 <= count; i += 8)
  {
    const uint64_t* block = rows + i * W;
    const uintptr_t ahead = reinterpret_cast<uintptr_t>(block) + kPrefetchWords * sizeof(uint64_t);
    for (size_t line = 0; line < W; ++line)  // the block's W cache lines, kPrefetchWords on (an address, not a pointer)
      _mm_prefetch(reinterpret_cast<const char*>(ahead + 64 * line), _MM_HINT_T0);
    __m512i nearest = packed[0]->wordSums(packed[0]->counts(block));
    for (size_t q = 1; q < nq; ++q)
      nearest = _mm512_min_epu64(nearest, packed[q]->wordSums(packed[q]->counts(block)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), _mm512_cvtepi64_epi32(nearest));
  }
  for (; i < count; ++i)
  {
    uint32_t nearest = pairAvx512Inline(queries[0], rows + i * W, W);
    for (size_t q = 1; q < nq; ++q)
      nearest = std::min(nearest, pairAvx512Inline(queries[q], rows + i * W, W));
    out[i] = nearest;
  }
}

// The difference of two rows' distances with one reduction: per word, count_a + 64 - count_b lies in 0 .. 128
// (a byte), so the bytes are subtracted before the horizontal sum and the bias 64 W after it.
template <size_t W>
struct PackedDifference
{
  PackedRows<W> a, b;

  __attribute__((target("avx512f,avx512bw"))) PackedDifference(const uint64_t* qa, const uint64_t* qb) : a(qa), b(qb) {}
  /// distance(qa, row at ra + k W) - distance(qb, row at rb + k W) for the eight rows k < 8.
  __attribute__((target("avx512f,avx512bw,avx512vbmi,avx512vpopcntdq"))) __m256i operator()(const uint64_t* ra,
                                                                                            const uint64_t* rb) const
  {
    return (*this)(a.counts(ra), rb);
  }
  /// The same with the first rows' bit counts already taken (a.counts).
  __attribute__((target("avx512f,avx512bw,avx512vbmi,avx512vpopcntdq"))) __m256i operator()(__m512i counts_a,
                                                                                            const uint64_t* rb) const
  {
    const __m512i bytes = _mm512_sub_epi8(_mm512_add_epi8(counts_a, _mm512_set1_epi8(64)), b.counts(rb));
    return _mm256_sub_epi32(a.sums(bytes), _mm256_set1_epi32(64 * W));
  }
};

template <size_t W>
__attribute__((target("avx512f,avx512bw,avx512vbmi,avx512vpopcntdq"))) void rowDifferenceAvx512Packed(
    const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b, size_t count, int32_t* out)
{
  const PackedDifference<W> difference(qa, qb);
  size_t i = 0;
  for (; i + 8 <= count; i += 8)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), difference(rows_a + i * W, rows_b + i * W));
  for (; i < count; ++i)
    out[i] = int32_t(pairAvx512Inline(qa, rows_a + i * W, W)) - int32_t(pairAvx512Inline(qb, rows_b + i * W, W));
}

// Eight sums of a chain step in a register: 32-bit sums in a ymm, 16-bit ones in an xmm (half the bytes).
template <typename Sum>
struct SumLanes;

template <>
struct SumLanes<uint32_t>
{
  using Vector = __m256i;
  __attribute__((target("avx512f,avx512vl"))) static Vector broadcast(uint32_t value)
  {
    return _mm256_set1_epi32(static_cast<int>(value));
  }
  /// Eight 64-bit distances in the lanes' width.
  __attribute__((target("avx512f,avx512vl"))) static Vector fromQwords(__m512i distances)
  {
    return _mm512_cvtepi64_epi32(distances);
  }
  /// Lane 7 of `before`, then lanes 0 .. 6 of `old`: the old sums one column to the left.
  __attribute__((target("avx512f,avx512vl"))) static Vector left(Vector old, Vector before)
  {
    return _mm256_alignr_epi32(old, before, 7);
  }
  __attribute__((target("avx512f,avx512vl"))) static Vector add(Vector a, Vector b)
  {
    return _mm256_add_epi32(a, b);
  }
  /// Modulo 2^32: a sum minus its leaving term is exact when the result fits.
  __attribute__((target("avx512f,avx512vl"))) static Vector sub(Vector a, Vector b)
  {
    return _mm256_sub_epi32(a, b);
  }
  __attribute__((target("avx512f,avx512vl"))) static Vector min(Vector a, Vector b)
  {
    return _mm256_min_epu32(a, b);
  }
};

template <>
struct SumLanes<uint16_t>
{
  using Vector = __m128i;
  __attribute__((target("avx512f,avx512vl"))) static Vector broadcast(uint32_t value)
  {
    return _mm_set1_epi16(static_cast<short>(value));
  }
  /// Every distance fits where the sums do (sums of 16 bits are for chains whose largest sum fits them).
  __attribute__((target("avx512f,avx512vl"))) static Vector fromQwords(__m512i distances)
  {
    return _mm512_cvtepi64_epi16(distances);
  }
  __attribute__((target("avx512f,avx512vl"))) static Vector left(Vector old, Vector before)
  {
    return _mm_alignr_epi8(old, before, 14);
  }
  __attribute__((target("avx512f,avx512vl"))) static Vector add(Vector a, Vector b)
  {
    return _mm_add_epi16(a, b);
  }
  /// Modulo 2^16: a sum minus its leaving term is exact when the result fits.
  __attribute__((target("avx512f,avx512vl"))) static Vector sub(Vector a, Vector b)
  {
    return _mm_sub_epi16(a, b);
  }
  __attribute__((target("avx512f,avx512vl"))) static Vector min(Vector a, Vector b)
  {
    return _mm_min_epu16(a, b);
  }
};

// One step of the sequence sums (hammingChainStep) on packed small rows, in place. Each block of eight rows is
// read once: its bit counts against the entering query qa go to the columns' new sums, those against the leaving
// query qb to `leaving`, L columns on. The leaving term of a column is then a small array in L1 instead of a
// second read of the rows L columns back: that second stream, 1-5 KB behind the first, cost 15-45 % at N = 1e7
// (more the longer L) and now nothing. Column i's old sum is loaded before it is overwritten, and the old sums
// of the eight columns before stay in a register, from which valignd / palignr takes the one to the left.
template <size_t W, typename Sum>
__attribute__((target("avx512f,avx512vl,avx512bw,avx512vbmi,avx512vpopcntdq"))) uint32_t chainStepAvx512Packed(
    const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L, uint32_t carry, Sum* sums,
    Sum* leaving)
{
  using Lanes = SumLanes<Sum>;
  using Vector = typename Lanes::Vector;
  const PackedRows<W> entering(qa), dropping(qb);
  Vector old_before = Lanes::broadcast(carry);  // lane 7: the old sum left of column i
  Vector minimum = Lanes::broadcast(UINT32_MAX);
  const size_t blocks = count / 8;
  for (size_t i = 0; i < blocks * 8; i += 8)
  {
    const uint64_t* block = rows + i * W;
    const Vector entering_terms = Lanes::fromQwords(entering.wordSums(entering.counts(block)));
    const Vector leaving_terms = Lanes::fromQwords(dropping.wordSums(dropping.counts(block)));
    // Stored before the load below: for L < 8 some of this block's columns drop terms of this block's rows.
    std::memcpy(leaving + i + L, &leaving_terms, sizeof(Vector));
    Vector gone, old;
    std::memcpy(&gone, leaving + i, sizeof(Vector));
    std::memcpy(&old, sums + i, sizeof(Vector));  // one unaligned vector load
    const Vector updated = Lanes::add(Lanes::left(old, old_before), Lanes::sub(entering_terms, gone));
    std::memcpy(sums + i, &updated, sizeof(Vector));
    minimum = Lanes::min(minimum, updated);
    old_before = old;
  }
  Sum lanes[8];
  std::memcpy(lanes, &minimum, sizeof(lanes));
  uint32_t smallest = blocks > 0 ? *std::min_element(lanes, lanes + 8) : UINT32_MAX;
  std::memcpy(lanes, &old_before, sizeof(lanes));
  Sum before = lanes[7];  // the carry itself when there was no whole block
  for (size_t i = blocks * 8; i < count; ++i)
  {
    leaving[i + L] = static_cast<Sum>(pairAvx512Inline(qb, rows + i * W, W));
    const Sum old = sums[i];
    sums[i] = static_cast<Sum>(before + pairAvx512Inline(qa, rows + i * W, W) - leaving[i]);
    smallest = std::min<uint32_t>(smallest, sums[i]);
    before = old;
  }
  return smallest;
}

bool hasVbmi()
{
  static const bool has =
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vbmi") && __builtin_cpu_supports("avx512vl");
  return has;
}

/// The lanes of the 8-word vector starting at word `first` that hold words of a `words`-word descriptor.
inline __mmask8 wordMask(size_t words, size_t first)
{
  return first >= words ? __mmask8(0) : words - first >= 8 ? __mmask8(0xff) : __mmask8((1u << (words - first)) - 1u);
}

__attribute__((target("avx512f,avx512vpopcntdq"))) void rowAvx512(const uint64_t* q, const uint64_t* rows,
                                                                  size_t stride, size_t words, size_t count,
                                                                  uint32_t* out)
{
  if (words >= 1 && words <= 8 && stride == words && hasVbmi())
  {
    using Packed = void (*)(const uint64_t*, const uint64_t*, size_t, uint32_t*);
    static const Packed packed[9] = {nullptr,
                                     rowAvx512Packed<1>,
                                     rowAvx512Packed<2>,
                                     rowAvx512Packed<3>,
                                     rowAvx512Packed<4>,
                                     rowAvx512Packed<5>,
                                     rowAvx512Packed<6>,
                                     rowAvx512Packed<7>,
                                     rowAvx512Packed<8>};
    packed[words](q, rows, count, out);
    return;
  }
  if (words > 24)
  {
    for (size_t i = 0; i < count; ++i)
      out[i] = pairAvx512Inline(q, rows + i * stride, words);
    return;
  }
  // Descriptors of up to three 512-bit vectors (LDB: 22 words): the query and the masks stay in registers
  // for the whole row instead of being reloaded for every stored frame.
  const __mmask8 m0 = wordMask(words, 0), m1 = wordMask(words, 8), m2 = wordMask(words, 16);
  const __m512i q0 = _mm512_maskz_loadu_epi64(m0, q), q1 = _mm512_maskz_loadu_epi64(m1, q + 8),
                q2 = _mm512_maskz_loadu_epi64(m2, q + 16);
  for (size_t i = 0; i < count; ++i)
  {
    const uint64_t* r = rows + i * stride;
    __m512i total = _mm512_popcnt_epi64(_mm512_xor_si512(q0, _mm512_maskz_loadu_epi64(m0, r)));
    total = _mm512_add_epi64(total, _mm512_popcnt_epi64(_mm512_xor_si512(q1, _mm512_maskz_loadu_epi64(m1, r + 8))));
    total = _mm512_add_epi64(total, _mm512_popcnt_epi64(_mm512_xor_si512(q2, _mm512_maskz_loadu_epi64(m2, r + 16))));
    out[i] = static_cast<uint32_t>(_mm512_reduce_add_epi64(total));
  }
}
__attribute__((target("avx512f,avx512vpopcntdq"))) void rowNearestAvx512(const uint64_t* const* queries, size_t nq,
                                                                         const uint64_t* rows, size_t stride,
                                                                         size_t words, size_t count, uint32_t* out)
{
  if (words >= 1 && words <= 8 && stride == words && nq <= kMostNearestQueries && hasVbmi())
  {
    using Packed = void (*)(const uint64_t* const*, size_t, const uint64_t*, size_t, uint32_t*);
    static const Packed packed[9] = {nullptr,
                                     rowNearestAvx512Packed<1>,
                                     rowNearestAvx512Packed<2>,
                                     rowNearestAvx512Packed<3>,
                                     rowNearestAvx512Packed<4>,
                                     rowNearestAvx512Packed<5>,
                                     rowNearestAvx512Packed<6>,
                                     rowNearestAvx512Packed<7>,
                                     rowNearestAvx512Packed<8>};
    packed[words](queries, nq, rows, count, out);
    return;
  }
  rowNearestOf<rowAvx512>(queries, nq, rows, stride, words, count, out);
}
// Both distances of every row from one read of it (the chain step's entering and leaving terms): up to three
// vectors (LDB: 22 words), both queries in registers, and one horizontal sum for the two, the second's
// per-lane counts (at most 192) added 32 bits up.
__attribute__((target("avx512f,avx512vpopcntdq"))) void rowPairAvx512(const uint64_t* qa, const uint64_t* qb,
                                                                      const uint64_t* rows, size_t stride, size_t words,
                                                                      size_t count, uint32_t* out_a, uint32_t* out_b)
{
  if (words > 24)
  {
    for (size_t i = 0; i < count; ++i)
    {
      out_a[i] = pairAvx512Inline(qa, rows + i * stride, words);
      out_b[i] = pairAvx512Inline(qb, rows + i * stride, words);
    }
    return;
  }
  const __mmask8 mask[3] = {wordMask(words, 0), wordMask(words, 8), wordMask(words, 16)};
  __m512i a[3], b[3];
  for (size_t v = 0; v < 3; ++v)
  {
    a[v] = _mm512_maskz_loadu_epi64(mask[v], qa + 8 * v);
    b[v] = _mm512_maskz_loadu_epi64(mask[v], qb + 8 * v);
  }
  for (size_t i = 0; i < count; ++i)
  {
    const uint64_t* r = rows + i * stride;
    __m512i total_a = _mm512_setzero_si512(), total_b = _mm512_setzero_si512();
    for (size_t v = 0; v < 3; ++v)
    {
      const __m512i row = _mm512_maskz_loadu_epi64(mask[v], r + 8 * v);
      total_a = _mm512_add_epi64(total_a, _mm512_popcnt_epi64(_mm512_xor_si512(a[v], row)));
      total_b = _mm512_add_epi64(total_b, _mm512_popcnt_epi64(_mm512_xor_si512(b[v], row)));
    }
    const uint64_t both =
        static_cast<uint64_t>(_mm512_reduce_add_epi64(_mm512_add_epi64(total_a, _mm512_slli_epi64(total_b, 32))));
    out_a[i] = static_cast<uint32_t>(both);
    out_b[i] = static_cast<uint32_t>(both >> 32);
  }
}

__attribute__((target("avx512f,avx512vpopcntdq"))) void rowDifferenceAvx512(const uint64_t* qa, const uint64_t* rows_a,
                                                                            const uint64_t* qb, const uint64_t* rows_b,
                                                                            size_t stride, size_t words, size_t count,
                                                                            int32_t* out)
{
  if (words >= 1 && words <= 8 && stride == words && hasVbmi())
  {
    using Packed = void (*)(const uint64_t*, const uint64_t*, const uint64_t*, const uint64_t*, size_t, int32_t*);
    static const Packed packed[9] = {nullptr,
                                     rowDifferenceAvx512Packed<1>,
                                     rowDifferenceAvx512Packed<2>,
                                     rowDifferenceAvx512Packed<3>,
                                     rowDifferenceAvx512Packed<4>,
                                     rowDifferenceAvx512Packed<5>,
                                     rowDifferenceAvx512Packed<6>,
                                     rowDifferenceAvx512Packed<7>,
                                     rowDifferenceAvx512Packed<8>};
    packed[words](qa, rows_a, qb, rows_b, count, out);
    return;
  }
  if (words > 24)
  {
    for (size_t i = 0; i < count; ++i)
      out[i] = int32_t(pairAvx512Inline(qa, rows_a + i * stride, words)) -
               int32_t(pairAvx512Inline(qb, rows_b + i * stride, words));
    return;
  }
  // Up to three vectors (LDB: 22 words): both queries and the masks in registers, as in rowAvx512, and the
  // two bit counts subtracted per lane before the one horizontal sum.
  const __mmask8 m0 = wordMask(words, 0), m1 = wordMask(words, 8), m2 = wordMask(words, 16);
  const __m512i a0 = _mm512_maskz_loadu_epi64(m0, qa), a1 = _mm512_maskz_loadu_epi64(m1, qa + 8),
                a2 = _mm512_maskz_loadu_epi64(m2, qa + 16);
  const __m512i b0 = _mm512_maskz_loadu_epi64(m0, qb), b1 = _mm512_maskz_loadu_epi64(m1, qb + 8),
                b2 = _mm512_maskz_loadu_epi64(m2, qb + 16);
  for (size_t i = 0; i < count; ++i)
  {
    const uint64_t* ra = rows_a + i * stride;
    const uint64_t* rb = rows_b + i * stride;
    __m512i d = _mm512_sub_epi64(_mm512_popcnt_epi64(_mm512_xor_si512(a0, _mm512_maskz_loadu_epi64(m0, ra))),
                                 _mm512_popcnt_epi64(_mm512_xor_si512(b0, _mm512_maskz_loadu_epi64(m0, rb))));
    d = _mm512_add_epi64(
        d, _mm512_sub_epi64(_mm512_popcnt_epi64(_mm512_xor_si512(a1, _mm512_maskz_loadu_epi64(m1, ra + 8))),
                            _mm512_popcnt_epi64(_mm512_xor_si512(b1, _mm512_maskz_loadu_epi64(m1, rb + 8)))));
    d = _mm512_add_epi64(
        d, _mm512_sub_epi64(_mm512_popcnt_epi64(_mm512_xor_si512(a2, _mm512_maskz_loadu_epi64(m2, ra + 16))),
                            _mm512_popcnt_epi64(_mm512_xor_si512(b2, _mm512_maskz_loadu_epi64(m2, rb + 16)))));
    out[i] = static_cast<int32_t>(_mm512_reduce_add_epi64(d));
  }
}
#pragma GCC diagnostic pop

template <typename Sum>
uint32_t chainStepAvx512(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                         size_t count, size_t L, uint32_t carry, Sum* sums, Sum* leaving)
{
  if (words >= 1 && words <= 8 && stride == words && hasVbmi())
  {
    using Packed =
        uint32_t (*)(const uint64_t*, const uint64_t*, const uint64_t*, size_t, size_t, uint32_t, Sum*, Sum*);
    static const Packed packed[9] = {nullptr,
                                     chainStepAvx512Packed<1, Sum>,
                                     chainStepAvx512Packed<2, Sum>,
                                     chainStepAvx512Packed<3, Sum>,
                                     chainStepAvx512Packed<4, Sum>,
                                     chainStepAvx512Packed<5, Sum>,
                                     chainStepAvx512Packed<6, Sum>,
                                     chainStepAvx512Packed<7, Sum>,
                                     chainStepAvx512Packed<8, Sum>};
    return packed[words](qa, qb, rows, count, L, carry, sums, leaving);
  }
  return chainStepOf<rowPairAvx512, Sum>(qa, qb, rows, stride, words, count, L, carry, sums, leaving);
}
}  // namespace

Kernel avx512Kernel()
{
  return {pairAvx512,
          rowAvx512,
          rowNearestAvx512,
          rowDifferenceAvx512,
          chainStepAvx512<uint32_t>,
          chainStepAvx512<uint16_t>};
}

}  // namespace hamming_kernels
}  // namespace openable

#endif  // x86
