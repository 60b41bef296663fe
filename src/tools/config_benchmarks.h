#pragma once

namespace openable_bench
{
/// Registers the benchmarks of the shipped configurations (config/*.yaml): describing one 640x480 image,
/// matching one frame against N stored places and reading those N places once, so that every ratio the
/// README gives is between two benchmarks of the same run.
void registerConfigBenchmarks();
}  // namespace openable_bench
