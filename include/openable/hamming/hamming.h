#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace openable
{
/// Hamming distance kernels. Every kernel returns exactly the same numbers; the fastest one the CPU
/// supports is chosen at run time. Only the portable kernel and those of the build's architecture are compiled
/// (x86: popcnt, avx2, avx512vpopcntdq; AArch64: neon); the others are never supported.
enum class HammingKernel
{
  kPortable,         ///< plain C++ bit counting (SWAR), any CPU
  kPopcnt,           ///< the POPCNT instruction, one 64-bit word at a time
  kAvx2,             ///< AVX2 nibble lookup (vpshufb) with horizontal sums
  kAvx512Vpopcntdq,  ///< AVX-512 VPOPCNTDQ
  kNeon,             ///< AArch64 NEON: per-byte counts (vcntq_u8) with pairwise widening sums
};

std::string kernelName(HammingKernel kernel);
/// Kernels this CPU can run, slowest first.
std::vector<HammingKernel> supportedKernels();
/// The kernel used by the functions without a kernel argument.
HammingKernel bestKernel();

/// popcount(a XOR b) over `words` 64-bit words.
uint32_t hamming(const uint64_t* a, const uint64_t* b, size_t words);
uint32_t hamming(HammingKernel kernel, const uint64_t* a, const uint64_t* b, size_t words);

/// out[i] = hamming(query, rows + i * stride, words) for i < count. Rows are `stride` words apart.
void hammingRow(const uint64_t* query, const uint64_t* rows, size_t stride, size_t words, size_t count, uint32_t* out);
void hammingRow(HammingKernel kernel, const uint64_t* query, const uint64_t* rows, size_t stride, size_t words,
                size_t count, uint32_t* out);

/// out[i] = the smallest hamming(queries[q], rows + i * stride, words) over q < nq (nq >= 1, else Error): a frame
/// and its views shifted sideways against each stored row, every row read once (on AVX-512 with packed small rows,
/// the minimum taken in registers).
void hammingRowNearest(const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t stride, size_t words,
                       size_t count, uint32_t* out);
void hammingRowNearest(HammingKernel kernel, const uint64_t* const* queries, size_t nq, const uint64_t* rows,
                       size_t stride, size_t words, size_t count, uint32_t* out);

/// out[i] = hamming(qa, rows_a + i * stride, words) - hamming(qb, rows_b + i * stride, words) for i < count:
/// the entering minus the leaving term of a sequence sum (sequence_matcher.h), both rows read in one pass and,
/// on AVX-512 with packed small rows, summed in one horizontal step.
void hammingRowDifference(const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b,
                          size_t stride, size_t words, size_t count, int32_t* out);
void hammingRowDifference(HammingKernel kernel, const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb,
                          const uint64_t* rows_b, size_t stride, size_t words, size_t count, int32_t* out);

/// One step of the sequence sums along diagonals (sequence_matcher.h), in place, reading each row once: for
/// i < count, with row i = rows + i * stride,
///   leaving[i + L] = hamming(qb, row i, words)       the term column i + L drops, L columns on
///   sums[i]        = before(i) + hamming(qa, row i, words) - leaving[i]
/// where before(0) = carry and before(i) is the old sums[i - 1]. `leaving` holds count + L terms: the caller
/// gives the first L (hamming(qb, row i - L) for i < L), and the last L are the next step's first. Returns the
/// smallest new sum (UINT32_MAX when count is 0). The caller ensures every new sum fits its type: the leaving
/// term is part of the old sum, and 16-bit sums are for chains whose largest sum fits 16 bits (half the state
/// read and written every frame).
uint32_t hammingChainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                          size_t count, size_t L, uint32_t carry, uint32_t* sums, uint32_t* leaving);
uint32_t hammingChainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                          size_t count, size_t L, uint32_t carry, uint16_t* sums, uint16_t* leaving);
uint32_t hammingChainStep(HammingKernel kernel, const uint64_t* qa, const uint64_t* qb, const uint64_t* rows,
                          size_t stride, size_t words, size_t count, size_t L, uint32_t carry, uint32_t* sums,
                          uint32_t* leaving);
uint32_t hammingChainStep(HammingKernel kernel, const uint64_t* qa, const uint64_t* qb, const uint64_t* rows,
                          size_t stride, size_t words, size_t count, size_t L, uint32_t carry, uint16_t* sums,
                          uint16_t* leaving);

/// Euclidean distance between two float vectors.
float l2Distance(const float* a, const float* b, size_t length);

}  // namespace openable
