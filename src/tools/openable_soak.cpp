// openable_soak: a long run of LoopDetector in loop-closure mode, to see what memory does over time
// (issue 9). Not a test: `make soak` runs it and doc/performance.md reports the figures.
//
//   openable_soak [--frames N] [--max-history H] [--every K]   (--help: the usage)
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
#include <optional>
#include <random>
#include <string>

#include "cli.h"
#include "openable/config.h"
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

const char kUsage[] = "usage: openable_soak [--frames N] [--max-history H] [--every K]\n"
                      "  --frames N       descriptors fed to LoopDetector (default 100000)\n"
                      "  --max-history H  the detector's max_history (default 0: unbounded)\n"
                      "  --every K        print the resident set size every K frames (default 10000)\n";

/// The options; nullopt for --help.
std::optional<Options> parseArguments(int argc, char** argv)
{
  constexpr int kMost = 100000000;
  Options o;
  openable::cli::Arguments args(argc, argv);
  while (args.next())
  {
    if (args.isHelp())
      return std::nullopt;
    if (args.is("--frames"))
      o.frames = args.integer<size_t>(0, kMost, "frames");
    else if (args.is("--max-history"))
      o.max_history = args.integer(0, kMost, "frames; 0: unbounded");
    else if (args.is("--every"))
      o.every = std::max<size_t>(1, args.integer<size_t>(0, kMost, "frames"));
    else
      args.unknown();
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
  return openable::cli::runTool({"openable_soak"}, argc, argv,
                                [](int argc, char** argv)
                                {
                                  const std::optional<Options> options = parseArguments(argc, argv);
                                  if (options)
                                    soak(*options);
                                  else
                                    std::cout << kUsage;
                                  return 0;
                                });
}
