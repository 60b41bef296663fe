// The portable part of the Hamming kernels: the public API of openable/hamming.h, the plain C++ kernel every
// CPU runs, and the run-time dispatch to the instruction-set kernels of this directory (hamming_kernels.h).
#include "openable/hamming/hamming.h"

#include <cmath>

#include "hamming/hamming_kernels.h"
#include "openable/error.h"

namespace openable
{
namespace hamming_kernels
{
namespace
{
inline uint32_t popcountPortable(uint64_t x)
{
  // SWAR bit count: pairs, nibbles, bytes, then one multiply sums the bytes.
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<uint32_t>((x * 0x0101010101010101ULL) >> 56);
}

uint32_t pairPortable(const uint64_t* a, const uint64_t* b, size_t words)
{
  uint32_t sum = 0;
  for (size_t i = 0; i < words; ++i)
    sum += popcountPortable(a[i] ^ b[i]);
  return sum;
}

void rowPortable(const uint64_t* q, const uint64_t* rows, size_t stride, size_t words, size_t count, uint32_t* out)
{
  for (size_t i = 0; i < count; ++i)
    out[i] = pairPortable(q, rows + i * stride, words);
}
}  // namespace

Kernel portableKernel()
{
  return kernelOf<pairPortable, rowPortable>();
}
}  // namespace hamming_kernels

namespace
{
using hamming_kernels::Kernel;

/// The kernels compiled for this architecture; those the CPU cannot run are never asked for (checkedKernel).
Kernel kernelFor(HammingKernel kernel)
{
  switch (kernel)
  {
#if defined(__x86_64__) || defined(__i386__)
    case HammingKernel::kPopcnt:
      return hamming_kernels::popcntKernel();
    case HammingKernel::kAvx2:
      return hamming_kernels::avx2Kernel();
    case HammingKernel::kAvx512Vpopcntdq:
      return hamming_kernels::avx512Kernel();
#endif
#if defined(__aarch64__)
    case HammingKernel::kNeon:
      return hamming_kernels::neonKernel();
#endif
    default:
      return hamming_kernels::portableKernel();
  }
}

Kernel checkedKernel(HammingKernel kernel)
{
  for (HammingKernel k : supportedKernels())
    if (k == kernel)
      return kernelFor(kernel);
  throw Error("Hamming kernel " + kernelName(kernel) + " is not supported by this CPU");
}

const Kernel& best()
{
  static const Kernel kernel = kernelFor(bestKernel());
  return kernel;
}
}  // namespace

std::string kernelName(HammingKernel kernel)
{
  switch (kernel)
  {
    case HammingKernel::kPortable:
      return "portable";
    case HammingKernel::kPopcnt:
      return "popcnt";
    case HammingKernel::kAvx2:
      return "avx2";
    case HammingKernel::kAvx512Vpopcntdq:
      return "avx512vpopcntdq";
    case HammingKernel::kNeon:
      return "neon";
  }
  return "unknown";
}

std::vector<HammingKernel> supportedKernels()
{
  std::vector<HammingKernel> kernels = {HammingKernel::kPortable};
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("popcnt"))
    kernels.push_back(HammingKernel::kPopcnt);
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt"))
    kernels.push_back(HammingKernel::kAvx2);
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq"))
    kernels.push_back(HammingKernel::kAvx512Vpopcntdq);
#endif
#if defined(__aarch64__)
  kernels.push_back(HammingKernel::kNeon);  // Advanced SIMD is part of every AArch64 CPU
#endif
  return kernels;
}

HammingKernel bestKernel()
{
  return supportedKernels().back();
}

uint32_t hamming(const uint64_t* a, const uint64_t* b, size_t words)
{
  return best().pair(a, b, words);
}

uint32_t hamming(HammingKernel kernel, const uint64_t* a, const uint64_t* b, size_t words)
{
  return checkedKernel(kernel).pair(a, b, words);
}

void hammingRow(const uint64_t* query, const uint64_t* rows, size_t stride, size_t words, size_t count, uint32_t* out)
{
  best().row(query, rows, stride, words, count, out);
}

void hammingRow(HammingKernel kernel, const uint64_t* query, const uint64_t* rows, size_t stride, size_t words,
                size_t count, uint32_t* out)
{
  checkedKernel(kernel).row(query, rows, stride, words, count, out);
}

void hammingRowNearest(const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t stride, size_t words,
                       size_t count, uint32_t* out)
{
  if (nq == 0)
    throw Error("hammingRowNearest: no query");
  best().nearest(queries, nq, rows, stride, words, count, out);
}

void hammingRowNearest(HammingKernel kernel, const uint64_t* const* queries, size_t nq, const uint64_t* rows,
                       size_t stride, size_t words, size_t count, uint32_t* out)
{
  if (nq == 0)
    throw Error("hammingRowNearest: no query");
  checkedKernel(kernel).nearest(queries, nq, rows, stride, words, count, out);
}

void hammingRowDifference(const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b,
                          size_t stride, size_t words, size_t count, int32_t* out)
{
  best().difference(qa, rows_a, qb, rows_b, stride, words, count, out);
}

void hammingRowDifference(HammingKernel kernel, const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb,
                          const uint64_t* rows_b, size_t stride, size_t words, size_t count, int32_t* out)
{
  checkedKernel(kernel).difference(qa, rows_a, qb, rows_b, stride, words, count, out);
}

uint32_t hammingChainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                          size_t count, size_t L, uint32_t carry, uint32_t* sums, uint32_t* leaving)
{
  return best().step(qa, qb, rows, stride, words, count, L, carry, sums, leaving);
}

uint32_t hammingChainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t stride, size_t words,
                          size_t count, size_t L, uint32_t carry, uint16_t* sums, uint16_t* leaving)
{
  return best().step16(qa, qb, rows, stride, words, count, L, carry, sums, leaving);
}

uint32_t hammingChainStep(HammingKernel kernel, const uint64_t* qa, const uint64_t* qb, const uint64_t* rows,
                          size_t stride, size_t words, size_t count, size_t L, uint32_t carry, uint32_t* sums,
                          uint32_t* leaving)
{
  return checkedKernel(kernel).step(qa, qb, rows, stride, words, count, L, carry, sums, leaving);
}

uint32_t hammingChainStep(HammingKernel kernel, const uint64_t* qa, const uint64_t* qb, const uint64_t* rows,
                          size_t stride, size_t words, size_t count, size_t L, uint32_t carry, uint16_t* sums,
                          uint16_t* leaving)
{
  return checkedKernel(kernel).step16(qa, qb, rows, stride, words, count, L, carry, sums, leaving);
}

float l2Distance(const float* a, const float* b, size_t length)
{
  double sum = 0.0;
  for (size_t i = 0; i < length; ++i)
  {
    const double d = double(a[i]) - double(b[i]);
    sum += d * d;
  }
  return static_cast<float>(std::sqrt(sum));
}

}  // namespace openable
