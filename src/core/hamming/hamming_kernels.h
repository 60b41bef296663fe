#pragma once

// The Hamming kernel table shared by the files of src/core/hamming (private to the core library):
//   hamming.cpp         the public API (include/openable/hamming.h), the portable kernel, run-time dispatch
//   hamming_x86.cpp     POPCNT and AVX2 kernels (x86 only)
//   hamming_avx512.cpp  AVX-512 VPOPCNTDQ kernels (x86 only)
//   hamming_neon.cpp    the NEON kernel (AArch64 only)
// Each instruction-set file compiles to nothing on other architectures, and each x86 kernel carries GCC's
// per-function target attribute, so the library builds without -march and picks a kernel at run time.

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace openable
{
namespace hamming_kernels
{
using PairFn = uint32_t (*)(const uint64_t*, const uint64_t*, size_t);
using RowFn = void (*)(const uint64_t*, const uint64_t*, size_t, size_t, size_t, uint32_t*);
using RowDifferenceFn = void (*)(const uint64_t*, const uint64_t*, const uint64_t*, const uint64_t*, size_t, size_t,
                                 size_t, int32_t*);
/// out[i] = the smallest distance of row i to any of the `nq` queries (a frame and its shifted views).
using RowNearestFn = void (*)(const uint64_t* const*, size_t, const uint64_t*, size_t, size_t, size_t, uint32_t*);
/// out_a[i] and out_b[i]: the distances of row i to qa and to qb (the chain step's entering and leaving terms).
using RowPairFn = void (*)(const uint64_t*, const uint64_t*, const uint64_t*, size_t, size_t, size_t, uint32_t*,
                           uint32_t*);
template <typename Sum>
using ChainStepFn = uint32_t (*)(const uint64_t*, const uint64_t*, const uint64_t*, size_t, size_t, size_t, size_t,
                                 uint32_t, Sum*, Sum*);

/// One kernel's entry points (the functions of hamming.h without the kernel argument).
struct Kernel
{
  PairFn pair;
  RowFn row;
  RowNearestFn nearest;
  RowDifferenceFn difference;
  ChainStepFn<uint32_t> step;
  ChainStepFn<uint16_t> step16;
};

/// The difference of two rows through a kernel's pair function (the kernels without a fused one).
template <PairFn pair>
void rowDifferenceOf(const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b,
                     size_t stride, size_t words, size_t count, int32_t* out)
{
  for (size_t i = 0; i < count; ++i)
    out[i] = int32_t(pair(qa, rows_a + i * stride, words)) - int32_t(pair(qb, rows_b + i * stride, words));
}

/// The nearest of several queries through a kernel's row function, a block of rows at a time (the block's rows
/// stay in cache for every query).
template <RowFn row>
void rowNearestOf(const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t stride, size_t words,
                  size_t count, uint32_t* out)
{
  constexpr size_t kBlock = 256;
  uint32_t other[kBlock];
  for (size_t begin = 0; begin < count; begin += kBlock)
  {
    const size_t n = std::min(kBlock, count - begin);
    const uint64_t* block = rows + begin * stride;
    row(queries[0], block, stride, words, n, out + begin);
    for (size_t q = 1; q < nq; ++q)
    {
      row(queries[q], block, stride, words, n, other);
      for (size_t i = 0; i < n; ++i)
        out[begin + i] = std::min(out[begin + i], other[i]);
    }
  }
}

/// Both rows of distances through a kernel's row function, one after the other (the rows stay in cache).
template <RowFn row>
void rowPairOf(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words, size_t count,
               uint32_t* out_a, uint32_t* out_b)
{
  row(qa, rows, stride, words, count, out_a);
  row(qb, rows, stride, words, count, out_b);
}

/// A chain step through a kernel's row pair function, a block of columns at a time.
template <RowPairFn row_pair, typename Sum>
uint32_t chainStepOf(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                     size_t count, size_t L, uint32_t carry, Sum* sums, Sum* leaving)
{
  constexpr size_t kBlock = 64;
  uint32_t entering[kBlock], dropped[kBlock];
  uint32_t smallest = UINT32_MAX;
  Sum before = static_cast<Sum>(carry);
  for (size_t begin = 0; begin < count; begin += kBlock)
  {
    const size_t n = std::min(kBlock, count - begin);
    row_pair(qa, qb, rows + begin * stride, stride, words, n, entering, dropped);
    // Stored before the loop below reads: for L < n some terms leave within this block.
    std::copy(dropped, dropped + n, leaving + begin + L);
    for (size_t i = 0; i < n; ++i)
    {
      const Sum old = sums[begin + i];
      sums[begin + i] = static_cast<Sum>(before + entering[i] - leaving[begin + i]);
      smallest = std::min<uint32_t>(smallest, sums[begin + i]);
      before = old;
    }
  }
  return smallest;
}

/// The complete kernel of a pair and a row function: the difference and the chain steps built from them.
template <PairFn pair, RowFn row>
Kernel kernelOf()
{
  return {pair, row, rowNearestOf<row>, rowDifferenceOf<pair>, chainStepOf<rowPairOf<row>, uint32_t>,
          chainStepOf<rowPairOf<row>, uint16_t>};
}

Kernel portableKernel();  // hamming.cpp, every architecture

#if defined(__x86_64__) || defined(__i386__)
Kernel popcntKernel();  // hamming_x86.cpp
Kernel avx2Kernel();    // hamming_x86.cpp
Kernel avx512Kernel();  // hamming_avx512.cpp
#endif

#if defined(__aarch64__)
Kernel neonKernel();  // hamming_neon.cpp
#endif

}  // namespace hamming_kernels
}  // namespace openable
