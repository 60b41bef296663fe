// openable_bench: description and matching cost, measured against a naive O(N * L) reference and against
// streaming the same descriptor bytes from memory once (the floor for any matcher that reads the history).
//
//   BM_Describe/<descriptor>      one 640x480 BGR image: preprocessing + description
//   BM_SequenceMatch/<N>/<L>      one frame of online sequence matching against N stored frames
//   BM_NaiveSequenceMatch/<N>/<L> the same row computed directly as sum_{k<L} d(t-k, j-k)
//   BM_MemoryRead/<N>             reading the N descriptors once (a sum over every word)
//   BM_ImageRead, BM_Config*      the shipped configurations: config_benchmarks.cpp
//
// Descriptors are LDB-sized (1386 bits in 22 words, 176 bytes). scripts/bench.sh turns the JSON output
// into the README table.

#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "config_benchmarks.h"
#include "openable/description/frame_describer.h"
#include "openable/descriptors/descriptor_registry.h"
#include "openable/matching/frame_metric.h"
#include "openable/hamming/hamming.h"
#include "openable/map/place_database.h"
#include "openable/matching/sequence_matcher.h"

namespace
{
using openable::DescriptorLayout;
using openable::PlaceDatabase;

DescriptorLayout ldbLayout()
{
  DescriptorLayout layout;
  layout.cell_length = 1386;
  layout.cell_words = 22;
  return layout;
}

/// A database of N random descriptors, built once per size and shared by the benchmarks.
const PlaceDatabase& database(size_t n)
{
  static std::vector<std::unique_ptr<PlaceDatabase>> cache;
  for (const auto& db : cache)
    if (db->size() == n)
      return *db;
  std::mt19937_64 rng(n);
  auto db = std::make_unique<PlaceDatabase>(ldbLayout());
  std::vector<uint64_t> d(22);
  for (size_t i = 0; i < n; ++i)
  {
    for (auto& w : d)
      w = rng();
    d[21] &= (uint64_t(1) << (1386 - 21 * 64)) - 1;
    db->add(d);
  }
  cache.push_back(std::move(db));
  return *cache.back();
}

std::vector<std::vector<uint64_t>> queries(size_t count)
{
  std::mt19937_64 rng(99);
  std::vector<std::vector<uint64_t>> q(count, std::vector<uint64_t>(22));
  for (auto& d : q)
    for (auto& w : d)
      w = rng();
  return q;
}

void setBytes(benchmark::State& state, size_t n)
{
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(n) * 22 * 8);
  state.counters["N"] = double(n);
}

void sequenceMatch(benchmark::State& state, size_t n, int L)
{
  const PlaceDatabase& db = database(n);
  openable::SequenceMatcher matcher(db.layout(), L, false);
  const auto q = queries(512);
  // Reach the steady state first: every chain full, so each frame both adds and drops a term.
  for (int i = 0; i <= L; ++i)
    matcher.match(q[i % q.size()].data(), db, n);
  size_t i = 0;
  for (auto _ : state)
  {
    matcher.match(q[i++ % q.size()].data(), db, n);
    benchmark::DoNotOptimize(matcher.forwardSum(n / 2));
  }
  setBytes(state, n);
  state.counters["state_bytes_per_column"] = 4 + 2;  // sum and count, updated in place
}

void naiveSequenceMatch(benchmark::State& state, size_t n, int L)
{
  const PlaceDatabase& db = database(n);
  const auto q = queries(size_t(L) + 1);
  std::vector<uint32_t> row(n);
  for (auto _ : state)
  {
    // S(t, j) = sum_{k < L} d(t - k, j - k), every term computed again for every frame.
    for (size_t j = 0; j < n; ++j)
    {
      uint32_t s = 0;
      for (int k = 0; k < L && size_t(k) <= j; ++k)
        s += openable::hamming(q[k].data(), db.descriptor(j - k), 22);
      row[j] = s;
    }
    benchmark::DoNotOptimize(row.data());
  }
  setBytes(state, n);
}

void memoryRead(benchmark::State& state, size_t n)
{
  const PlaceDatabase& db = database(n);
  const uint64_t* words = db.data();
  const size_t count = n * 22;
  for (auto _ : state)
  {
    uint64_t x = 0;
    for (size_t i = 0; i < count; ++i)
      x += words[i];
    benchmark::DoNotOptimize(x);
  }
  setBytes(state, n);
}

void describe(benchmark::State& state, const std::string& name)
{
  openable::Config config;
  config.descriptor = name;
  const openable::FrameDescriber describer(config);
  // A real image at the size the design targets (Gardens Point, resized to 640x480); noise if missing.
  cv::Mat image = cv::imread(std::string(OPENABLE_SOURCE_DIR) + "/data/sample/day_right/Image100.jpg");
  if (image.empty())
  {
    image.create(480, 640, CV_8UC3);
    cv::randu(image, 0, 255);
  }
  cv::resize(image, image, cv::Size(640, 480));
  for (auto _ : state)
    benchmark::DoNotOptimize(describer.describeImage(image).data());
  state.SetItemsProcessed(state.iterations());
}

void describeInvariant(benchmark::State& state)
{
  openable::Config config;
  config.illumination_invariance = true;
  const openable::FrameDescriber describer(config);
  cv::Mat image(480, 640, CV_8UC3);
  cv::randu(image, 1, 255);
  for (auto _ : state)
    benchmark::DoNotOptimize(describer.describeImage(image).data());
  state.SetItemsProcessed(state.iterations());
}

void registerAll()
{
  for (const auto& row : openable::descriptorRegistry())
    if (!row.needs_disparity)  // a mono image has no disparity to describe
      benchmark::RegisterBenchmark((std::string("BM_Describe/") + row.name).c_str(), describe, std::string(row.name))
          ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_Describe/LDB_illumination_invariant", describeInvariant)
      ->Unit(benchmark::kMicrosecond);
  const size_t sizes[] = {1000, 10000, 100000, 1000000};
  const int lengths[] = {1, 10, 300};
  for (size_t n : sizes)
  {
    for (int L : lengths)
    {
      const std::string suffix = std::to_string(n) + "/" + std::to_string(L);
      benchmark::RegisterBenchmark(("BM_SequenceMatch/" + suffix).c_str(), sequenceMatch, n, L)
          ->Unit(benchmark::kMicrosecond);
      if (n * size_t(L) <= 3000000)  // the naive reference is O(N * L): only where it finishes in seconds
        benchmark::RegisterBenchmark(("BM_NaiveSequenceMatch/" + suffix).c_str(), naiveSequenceMatch, n, L)
            ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark(("BM_MemoryRead/" + std::to_string(n)).c_str(), memoryRead, n)
        ->Unit(benchmark::kMicrosecond);
  }
}
}  // namespace

int main(int argc, char** argv)
{
  registerAll();
  openable_bench::registerConfigBenchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv))
    return 1;
  benchmark::AddCustomContext("hamming_kernel", openable::kernelName(openable::bestKernel()));
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
