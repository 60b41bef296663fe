// The shipped configurations as a user runs them (issue 11):
//
//   BM_ImageRead/640x480              one pass over the bytes of a 640x480 BGR image (the floor for describing it)
//   BM_ConfigDescribe/<config>        preprocessing + description of that image with config/<config>.yaml
//   BM_ConfigMatch/<config>/<N>       one frame of sequence matching (the config's L, descriptor and direction)
//                                     against N stored places, and the choice of its top_k distinct candidates
//                                     as LoopDetector makes it: the scan of the history every frame pays
//   BM_ConfigPaceMatch/<config>/<N>   the same frame with sequences at any pace (PaceMatcher, the config's max_pace,
//                                     pace_penalty and pace_tolerance; max_pace 3 when the config says 1), the
//                                     matcher the shipped configurations run (with their slip_penalty and
//                                     pace_prior), while no loop is published: a robot on new ground; with
//                                     the config's lateral_shift, each query with its two shifted views
//   BM_ConfigPaceMatchPublished/<config>/<N>
//                                     BM_ConfigPaceMatch while a run is published: no pace prior to add (configs
//                                     whose pace_prior is not 0)
//   BM_ConfigPaceMatchNoSlip/<config>/<N>
//                                     BM_ConfigPaceMatch with slip_penalty 0: what following a path one place off
//                                     its line costs a frame (configs whose slip_penalty is not 0)
//   BM_ConfigPaceMatchShifted/default/<N>
//                                     BM_ConfigPaceMatch with two shifted views a query (lateral_shift > 0)
//   BM_ConfigMemoryRead/<config>/<N>  reading those N descriptors once (a sum over every word)
//   BM_ConfigTwoChannelMatch/<config>/<N>
//                                     a config with a view channel (view_channel_shift): BM_ConfigPaceMatch and the
//                                     view channel's frame (its own map of crops on view_channel_bits, each query
//                                     with two shifted views), what a frame of the detector pays, searching
//   BM_ConfigTwoChannelRead/<config>/<N>
//                                     reading both channels' maps once
//   BM_ConfigMatchLength/gardens_point/10000000/<L>
//                                     BM_ConfigMatch with another sequence length: a frame reads each descriptor
//                                     once, so its cost should not depend on L
//   BM_ConfigPaceMatchLength/default/1000000/<L>
//                                     BM_ConfigPaceMatch with another sequence length: the paths' memory is a
//                                     weight (a = 1 - 1/L), not a window, so neither should its cost
//
// N = 1e5, 1e6, and 1e7 when a place takes at most 64 bytes (a 1e7-place map of HOG would be 13 GB).
#include "config_benchmarks.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/map/place_database.h"
#include "openable/matching/pace_matcher.h"
#include "openable/matching/sequence_matcher.h"

namespace openable_bench
{
namespace
{
const char* const kConfigs[] = {"gardens_point", "nordland", "default"};

openable::Config shipped(const std::string& name)
{
  return openable::Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/" + name + ".yaml");
}

/// A real image at the size the design targets (Gardens Point, resized to 640x480); noise if missing.
const cv::Mat& vgaImage()
{
  static const cv::Mat image = []
  {
    cv::Mat image = cv::imread(std::string(OPENABLE_SOURCE_DIR) + "/data/sample/day_right/Image100.jpg");
    if (image.empty())
    {
      image.create(480, 640, CV_8UC3);
      cv::randu(image, 0, 255);
    }
    cv::resize(image, image, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    return image;
  }();
  return image;
}

/// One random descriptor of the layout: random bits (unused bits of a cell 0), or random unit vectors.
void randomDescriptor(const openable::DescriptorLayout& layout, std::mt19937_64& rng, uint64_t* out)
{
  for (int cell = 0; cell < layout.cells; ++cell)
  {
    uint64_t* words = out + size_t(cell) * layout.cell_words;
    if (layout.binary)
    {
      for (int w = 0; w < layout.cell_words; ++w)
        words[w] = rng();
      if (layout.cell_length % 64)
        words[layout.cell_words - 1] &= (uint64_t(1) << (layout.cell_length % 64)) - 1;
      continue;
    }
    std::vector<float> values(size_t(layout.cell_words) * 2, 0.0f);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    double norm = 0.0;
    for (int i = 0; i < layout.cell_length; ++i)
    {
      values[i] = uniform(rng);
      norm += double(values[i]) * values[i];
    }
    for (int i = 0; i < layout.cell_length; ++i)
      values[i] = static_cast<float>(values[i] / std::sqrt(norm));
    std::memcpy(words, values.data(), sizeof(float) * values.size());
  }
}

/// N random places of `layout`, held as a map loaded from a file is: exactly its frames.
std::unique_ptr<openable::PlaceDatabase> randomMap(const openable::DescriptorLayout& layout, size_t n, uint64_t seed)
{
  auto db = std::make_unique<openable::PlaceDatabase>(layout);
  std::mt19937_64 rng(seed);
  openable::FrameDescriptor d(layout.frameWords());
  for (size_t i = 0; i < n; ++i)
  {
    randomDescriptor(layout, rng, d.data());
    db->add(d);
  }
  db->shrinkToFit();
  return db;
}

/// A map of N random places in the layout of `config`, built once per (config, N): the largest take
/// seconds to fill and gigabytes to hold, so only the most recent one is kept.
const openable::PlaceDatabase& database(const std::string& config_name, size_t n)
{
  static std::string cached_name;
  static std::unique_ptr<openable::PlaceDatabase> cached;
  if (cached && cached_name == config_name && cached->size() == n)
    return *cached;
  cached.reset();
  cached = randomMap(openable::FrameDescriber(shipped(config_name)).layout(), n, n);
  cached_name = config_name;
  return *cached;
}

/// The one pass over a map's first N descriptors a frame's match is compared with (a sum over every word).
uint64_t sumOfWords(const openable::PlaceDatabase& db, size_t n)
{
  const uint64_t* words = db.data();
  const size_t count = n * db.layout().frameWords();
  uint64_t x = 0;
  for (size_t i = 0; i < count; ++i)
    x += words[i];
  return x;
}

/// Bytes moved and the map's size, for the maps a frame reads (one, or each channel's), of the same N places.
void setBytes(benchmark::State& state, std::initializer_list<const openable::PlaceDatabase*> maps)
{
  size_t frame_bytes = 0, map_bytes = 0;
  for (const openable::PlaceDatabase* db : maps)
  {
    frame_bytes += sizeof(uint64_t) * db->layout().frameWords();
    map_bytes += db->bytes();
  }
  const size_t n = (*maps.begin())->size();
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(n * frame_bytes));
  state.counters["N"] = double(n);
  state.counters["descriptor_bytes"] = double(frame_bytes);
  state.counters["map_bytes"] = double(map_bytes);
}

void setBytes(benchmark::State& state, const openable::PlaceDatabase& db)
{
  setBytes(state, {&db});
}

void imageRead(benchmark::State& state)
{
  const cv::Mat& image = vgaImage();
  const size_t bytes = image.total() * image.elemSize();
  for (auto _ : state)
  {
    // 32-bit lanes the compiler vectorises: the cost of touching every byte once.
    uint32_t sum = 0;
    for (int y = 0; y < image.rows; ++y)
    {
      const uint8_t* row = image.ptr<uint8_t>(y);
      for (int x = 0; x < image.cols * image.channels(); ++x)
        sum += row[x];
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes));
}

void configDescribe(benchmark::State& state, const std::string& name)
{
  const openable::FrameDescriber describer(shipped(name));
  const cv::Mat& image = vgaImage();
  for (auto _ : state)
    benchmark::DoNotOptimize(describer.describeImage(image).data());
  state.SetItemsProcessed(state.iterations());
  state.counters["descriptor_bytes"] = double(sizeof(uint64_t) * describer.layout().frameWords());
}

/// `sequence_length` 0: the config's own.
void configMatch(benchmark::State& state, const std::string& name, size_t n, int sequence_length)
{
  const openable::Config config = shipped(name);
  const int L = sequence_length > 0 ? sequence_length : config.sequence_length;
  const openable::PlaceDatabase& db = database(name, n);
  openable::SequenceMatcher matcher(db.layout(), L, config.bidirectional);
  std::mt19937_64 rng(99);
  std::vector<openable::FrameDescriptor> queries(64, openable::FrameDescriptor(db.layout().frameWords()));
  for (auto& q : queries)
    randomDescriptor(db.layout(), rng, q.data());
  // The steady state first: every chain full, so each frame both adds and drops a term.
  for (int i = 0; i <= L; ++i)
    matcher.match(queries[i % queries.size()].data(), db, n);
  size_t i = 0;
  std::vector<size_t> candidates;
  const size_t wanted = size_t(std::max(config.top_k, 2));
  for (auto _ : state)
  {
    matcher.match(queries[i++ % queries.size()].data(), db, n);
    matcher.smallestDistinct(wanted, size_t(config.uniqueness_window), L, candidates);
    benchmark::DoNotOptimize(candidates.data());
  }
  setBytes(state, db);
}

/// One frame of a channel as PaceMatcher runs it against `db`: a random query with `views` shifted views behind it
/// (the detector matches them all, the smallest distance counts), then the choice of its top_k candidates.
class PaceFrame
{
public:
  PaceFrame(const openable::Config& config, const openable::PlaceDatabase& db, size_t n, bool slip, bool searching,
            int sequence_length, size_t views)
    : config_(config),
      db_(db),
      n_(n),
      views_(views),
      words_(db.layout().frameWords()),
      matcher_(db.layout(), sequence_length, config.bidirectional, paceOptions(config, slip))
  {
    matcher_.setSearching(searching);
    std::mt19937_64 rng(99);
    queries_.assign(64, openable::FrameDescriptor(words_ * (1 + views)));
    for (auto& q : queries_)
      for (size_t v = 0; v <= views; ++v)
        randomDescriptor(db.layout(), rng, q.data() + v * words_);
    for (int i = 0; i < 3; ++i)  // past the first row, which has no path behind it
      match();
  }
  void operator()()
  {
    match();
    matcher_.smallestDistinct(size_t(std::max(config_.top_k, 2)), size_t(config_.uniqueness_window), 1, candidates_);
    benchmark::DoNotOptimize(candidates_.data());
  }
  size_t paces() const
  {
    return matcher_.paces().size();
  }

private:
  static openable::PaceOptions paceOptions(const openable::Config& config, bool slip)
  {
    openable::PaceOptions pace;
    pace.max_pace = std::max(3, config.max_pace);
    pace.penalty = static_cast<float>(config.pace_penalty);
    pace.tolerance = config.pace_tolerance;
    pace.slip = slip ? static_cast<float>(config.slip_penalty) : 0.0f;
    pace.prior = static_cast<float>(config.pace_prior);
    return pace;
  }
  void match()
  {
    const openable::FrameDescriptor& q = queries_[next_++ % queries_.size()];
    matcher_.matchShifted(q.data(), q.data() + words_, views_, db_, n_);
  }
  openable::Config config_;
  const openable::PlaceDatabase& db_;
  size_t n_, views_, words_;
  openable::PaceMatcher matcher_;
  std::vector<openable::FrameDescriptor> queries_;
  std::vector<size_t> candidates_;
  size_t next_ = 0;
};

/// `sequence_length` 0: the config's own. `shifted`: each query with two shifted views, whatever the config's
/// lateral_shift says (the views are matched where it is above 0). The whole image's channel alone.
void configPaceMatch(benchmark::State& state, const std::string& name, size_t n, bool slip, bool searching,
                     int sequence_length, bool shifted)
{
  const openable::Config config = shipped(name);
  const openable::PlaceDatabase& db = database(name, n);
  const size_t views = shifted || config.lateral_shift > 0.0 ? 2 : 0;
  PaceFrame frame(config, db, n, slip, searching, sequence_length > 0 ? sequence_length : config.sequence_length, views);
  for (auto _ : state)
    frame();
  setBytes(state, db);
  state.counters["paces"] = double(frame.paces());
  state.counters["shifted_views"] = double(views);
}

/// The view channel's map (Config::view_channel_shift) of N random places, beside database()'s.
const openable::PlaceDatabase& viewDatabase(const std::string& config_name, size_t n)
{
  static std::unique_ptr<openable::PlaceDatabase> cached;
  if (!cached || cached->size() != n)
  {
    cached.reset();
    cached = randomMap(openable::descriptorLayout(shipped(config_name).viewChannel()), n, n + 1);
  }
  return *cached;
}

/// What a frame of a configuration with a view channel pays: the whole image's channel and the view channel (its
/// places' crops on view_channel_bits, each query with two shifted views), searching. Bytes: both maps.
void configTwoChannelMatch(benchmark::State& state, const std::string& name, size_t n)
{
  const openable::Config config = shipped(name);
  const openable::Config views = config.viewChannel();
  const openable::PlaceDatabase& whole_db = database(name, n);
  const openable::PlaceDatabase& view_db = viewDatabase(name, n);
  PaceFrame whole(config, whole_db, n, true, true, config.sequence_length, 0);
  PaceFrame viewed(views, view_db, n, true, true, views.sequence_length, 2);
  for (auto _ : state)
  {
    whole();
    viewed();
  }
  setBytes(state, {&whole_db, &view_db});
}

/// One pass over both channels' descriptors.
void configTwoChannelRead(benchmark::State& state, const std::string& name, size_t n)
{
  const openable::PlaceDatabase& whole_db = database(name, n);
  const openable::PlaceDatabase& view_db = viewDatabase(name, n);
  for (auto _ : state)
    benchmark::DoNotOptimize(sumOfWords(whole_db, n) + sumOfWords(view_db, n));
  setBytes(state, {&whole_db, &view_db});
}

void configMemoryRead(benchmark::State& state, const std::string& name, size_t n)
{
  const openable::PlaceDatabase& db = database(name, n);
  for (auto _ : state)
    benchmark::DoNotOptimize(sumOfWords(db, n));
  setBytes(state, db);
}
}  // namespace

void registerConfigBenchmarks()
{
  benchmark::RegisterBenchmark("BM_ImageRead/640x480", imageRead)->Unit(benchmark::kMicrosecond);
  for (const std::string name : kConfigs)
    benchmark::RegisterBenchmark(("BM_ConfigDescribe/" + name).c_str(), configDescribe, name)
        ->Unit(benchmark::kMicrosecond);
  // Grouped by (config, N), match and read next to each other: the map of one size is built once.
  for (const std::string name : kConfigs)
  {
    const size_t frame_bytes = sizeof(uint64_t) * openable::FrameDescriber(shipped(name)).layout().frameWords();
    for (size_t n : {size_t(100000), size_t(1000000), size_t(10000000)})
    {
      if (n > 1000000 && frame_bytes > 64)
        continue;
      const std::string suffix = name + "/" + std::to_string(n);
      benchmark::RegisterBenchmark(("BM_ConfigMatch/" + suffix).c_str(), configMatch, name, n, 0)
          ->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark(("BM_ConfigPaceMatch/" + suffix).c_str(), configPaceMatch, name, n, true, true, 0,
                                   false)
          ->Unit(benchmark::kMillisecond);
      if (shipped(name).pace_prior > 0.0)  // else BM_ConfigPaceMatch is this frame already
        benchmark::RegisterBenchmark(("BM_ConfigPaceMatchPublished/" + suffix).c_str(), configPaceMatch, name, n, true,
                                     false, 0, false)
            ->Unit(benchmark::kMillisecond);
      if (shipped(name).slip_penalty > 0.0)  // else BM_ConfigPaceMatch is this frame already
        benchmark::RegisterBenchmark(("BM_ConfigPaceMatchNoSlip/" + suffix).c_str(), configPaceMatch, name, n, false,
                                     true, 0, false)
            ->Unit(benchmark::kMillisecond);
      if (name == "default")  // lateral_shift 0.12: three distances a place from one read of the map
        benchmark::RegisterBenchmark(("BM_ConfigPaceMatchShifted/" + suffix).c_str(), configPaceMatch, name, n, true,
                                     true, 0, true)
            ->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark(("BM_ConfigMemoryRead/" + suffix).c_str(), configMemoryRead, name, n)
          ->Unit(benchmark::kMillisecond);
      if (shipped(name).view_channel_shift > 0.0)  // both channels a frame, against a read of both maps
      {
        benchmark::RegisterBenchmark(("BM_ConfigTwoChannelMatch/" + suffix).c_str(), configTwoChannelMatch, name, n)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("BM_ConfigTwoChannelRead/" + suffix).c_str(), configTwoChannelRead, name, n)
            ->Unit(benchmark::kMillisecond);
      }
      if (name == "default" && n == 1000000)
        for (int L : {10, 30, 100, 300})
          benchmark::RegisterBenchmark(("BM_ConfigPaceMatchLength/" + suffix + "/" + std::to_string(L)).c_str(),
                                       configPaceMatch, name, n, true, true, L, false)
              ->Unit(benchmark::kMillisecond);
      if (name != "gardens_point" || n != 10000000)
        continue;
      for (int L : {10, 50, 100, 300})  // 300: longer than a chunk of columns (256)
        benchmark::RegisterBenchmark(("BM_ConfigMatchLength/" + suffix + "/" + std::to_string(L)).c_str(), configMatch,
                                     name, n, L)
            ->Unit(benchmark::kMillisecond);
    }
  }
}

}  // namespace openable_bench
