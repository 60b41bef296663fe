// The portable kernel of PaceMatcher and the run-time choice of a kernel (pace_kernels.h).
#include "pace_kernels.h"

#include <string>

#include "openable/error.h"

namespace openable
{
namespace pace_kernels
{
ChunkSums chunkPortable(const Chunk& chunk)
{
  ChunkSums sums;
  for (size_t i = 0; i < chunk.m; ++i)
    prepare(chunk, i);
  // The last place first: a forward row is updated in place, and a place reads the places before it.
  for (size_t i = chunk.m; i-- > 0;)
    update(chunk, i, sums);
  return sums;
}

bool supported(PaceKernel kernel)
{
  switch (kernel)
  {
    case PaceKernel::kBest:
    case PaceKernel::kPortable:
      return true;
#if defined(__x86_64__) || defined(__i386__)
    case PaceKernel::kAvx2:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx2");
    case PaceKernel::kAvx512:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw");
#endif
    default:
      return false;
  }
}

namespace
{
ChunkFn fastest(long reach)
{
#if defined(__x86_64__) || defined(__i386__)
  if (supported(PaceKernel::kAvx512) && reach <= kAvx512Reach)
    return chunkAvx512;
  if (supported(PaceKernel::kAvx2))
    return chunkAvx2;
#endif
  return chunkPortable;
}
}  // namespace

void requireSupported(PaceKernel kernel)
{
  if (!supported(kernel))
    throw Error("pace kernel " + paceKernelName(kernel) + " is not supported by this CPU");
}

ChunkFn kernelFor(PaceKernel kernel, long reach)
{
  requireSupported(kernel);
  if (kernel == PaceKernel::kAvx512 && reach > kAvx512Reach)
    throw Error("the avx512bw pace kernel reads up to " + std::to_string(kAvx512Reach) + " places behind; max_pace " +
                std::to_string(reach - 1) + " needs " + std::to_string(reach));
  switch (kernel)
  {
#if defined(__x86_64__) || defined(__i386__)
    case PaceKernel::kAvx2:
      return chunkAvx2;
    case PaceKernel::kAvx512:
      return chunkAvx512;
#endif
    case PaceKernel::kPortable:
      return chunkPortable;
    default:
      return fastest(reach);
  }
}
}  // namespace pace_kernels

std::string paceKernelName(PaceKernel kernel)
{
  switch (kernel)
  {
    case PaceKernel::kBest:
      return "best";
    case PaceKernel::kPortable:
      return "portable";
    case PaceKernel::kAvx2:
      return "avx2";
    case PaceKernel::kAvx512:
      return "avx512bw";
  }
  return "unknown";
}

std::vector<PaceKernel> supportedPaceKernels()
{
  std::vector<PaceKernel> kernels;
  for (PaceKernel k : {PaceKernel::kPortable, PaceKernel::kAvx2, PaceKernel::kAvx512})
    if (pace_kernels::supported(k))
      kernels.push_back(k);
  return kernels;
}

}  // namespace openable
