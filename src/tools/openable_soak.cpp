// openable_soak: a long run of LoopDetector in loop-closure mode, to see what memory does over time
// (issue 9). Not a test: `make soak` runs it and doc/performance.md reports the figures.
//
//   openable_soak [--frames N] [--max-history H] [--every K]
//
// Feeds N random LDB-sized descriptors (default 100,000) through LoopDetector with the default
// configuration and max_history H (default 0 = unbounded) and prints the resident set size every K frames
// (default 10,000) with the bytes per frame it grew since the first report. One run per process, so
// memory freed by an earlier run cannot hide growth. Random descriptors cost nothing to make, so the run
// measures the detector, not description.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <string>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/detection/loop_detector.h"

namespace
{
struct Options
{
  size_t frames = 100000;
  int max_history = 0;
  size_t every = 10000;
};

size_t parseCount(const std::string& flag, const char* text)
{
  char* end = nullptr;
  const long long value = std::strtoll(text, &end, 10);
  if (end == text || *end != '\0' || value < 0 || value > 100000000)
    throw openable::Error(flag + ": '" + text + "' is not a count in [0, 100000000]");
  return static_cast<size_t>(value);
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string flag = argv[i];
    if (i + 1 >= argc)
      throw openable::Error(flag + " needs a value (usage: openable_soak [--frames N] [--max-history H] [--every K])");
    const size_t value = parseCount(flag, argv[++i]);
    if (flag == "--frames")
      o.frames = value;
    else if (flag == "--max-history")
      o.max_history = static_cast<int>(value);
    else if (flag == "--every")
      o.every = std::max<size_t>(1, value);
    else
      throw openable::Error("unknown argument '" + flag + "'");
  }
  return o;
}

/// Resident set size in bytes (second field of /proc/self/statm, in pages).
size_t residentBytes()
{
  std::ifstream statm("/proc/self/statm");
  size_t total = 0, resident = 0;
  statm >> total >> resident;
  return resident * static_cast<size_t>(::sysconf(_SC_PAGESIZE));
}

void soak(const Options& o)
{
  openable::Config config;
  config.max_history = o.max_history;
  const openable::DescriptorLayout layout = openable::FrameDescriber(config).layout();
  openable::LoopDetector detector(config);
  std::mt19937_64 rng(42);
  openable::FrameDescriptor descriptor(layout.frameWords());
  // Bits past cell_length stay 0, as the describer leaves them.
  const int tail_bits = layout.cell_length % 64;
  const uint64_t last_word_mask = tail_bits ? (uint64_t(1) << tail_bits) - 1 : ~uint64_t(0);

  std::cout << "max_history " << o.max_history << (o.max_history ? "" : " (unbounded)") << ": "
            << layout.frameWords() * 8 << "-byte descriptors\n"
            << "  frames   stored   RSS MB   bytes/frame since first report   s\n";
  // Before any frame: the libraries and the detector's fixed buffers, the floor every figure stands on.
  std::cout << "       0        0  " << std::fixed << std::setprecision(1) << std::setw(7) << residentBytes() / 1e6
            << "\n";
  const auto start = std::chrono::steady_clock::now();
  size_t first_rss = 0, first_frame = 0;
  for (size_t frame = 1; frame <= o.frames; ++frame)
  {
    for (auto& w : descriptor)
      w = rng();
    descriptor.back() &= last_word_mask;
    openable::FrameInfo info;
    info.source = "frame_" + std::to_string(frame);  // a name like a file's, as the tools give
    detector.process(descriptor, info);
    if (frame % o.every != 0 && frame != o.frames)
      continue;
    const size_t rss = residentBytes();
    if (first_frame == 0)
    {
      first_rss = rss;
      first_frame = frame;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char line[160];
    std::snprintf(line, sizeof(line), "  %6zu  %7zu  %7.1f   %30.0f   %5.1f\n", frame, detector.map().frameCount(),
                  rss / 1e6,
                  frame > first_frame ? (double(rss) - double(first_rss)) / double(frame - first_frame) : 0.0, seconds);
    std::cout << line << std::flush;
  }
}
}  // namespace

int main(int argc, char** argv)
{
  try
  {
    soak(parseArguments(argc, argv));
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "openable_soak: error: " << e.what() << "\n";
    return 1;
  }
}
