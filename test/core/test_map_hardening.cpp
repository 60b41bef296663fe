// Issue 9 (hardening): maps that are not what they claim are refused by PlaceDatabase::load with an
// openable::Error naming the file, before they cost memory or reach FrameMetric. The repro maps are in
// test/data/repro (README there).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "memory_limit.h"
#include "openable/config.h"
#include "openable/error.h"
#include "openable/matching/frame_metric.h"
#include "openable/map/place_database.h"

using namespace openable;
namespace fs = std::filesystem;

namespace
{
std::string repro(const std::string& name)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/test/data/repro/" + name;
}

/// The message of the openable::Error `action` throws; fails the test for anything else.
template <typename Action>
std::string errorOf(Action action)
{
  try
  {
    action();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  catch (const std::exception& e)
  {
    ADD_FAILURE() << "not an openable::Error: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no error";
  return "";
}

template <typename T>
void put(std::string& bytes, T value)
{
  bytes.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// A map file in the project's format (see PlaceDatabase::save) around `payload` (metadata and
/// descriptors, as crafted by the test), with a valid checksum so only the contents are wrong.
std::string craftMap(int32_t cell_length, int32_t cell_words, uint64_t capacity, uint64_t frames,
                     const std::string& payload)
{
  std::string bytes = "OPNABLEM";
  put<uint32_t>(bytes, 1);  // version
  put<uint32_t>(bytes, 1);  // binary
  put<int32_t>(bytes, cell_length);
  put<int32_t>(bytes, cell_words);
  put<int32_t>(bytes, 1);  // cells
  put<int32_t>(bytes, 1);  // blocks
  put<uint64_t>(bytes, capacity);
  put<uint64_t>(bytes, 0);  // first id
  put<uint64_t>(bytes, frames);
  put<uint64_t>(bytes, 0);  // configuration: empty
  bytes += payload;
  uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a, as the format's checksum
  for (unsigned char c : bytes)
  {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  put<uint64_t>(bytes, hash);
  return bytes;
}

std::string writeTemp(const std::string& name, const std::string& bytes)
{
  const std::string path = testing::TempDir() + "/openable_test_map_hardening_" + name;
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}
}  // namespace

TEST(MapHardening, FrameWordsDoNotOverflowInt)
{
  DescriptorLayout layout;
  layout.cell_words = 65536;
  layout.cells = 65536;
  EXPECT_EQ(uint64_t(layout.frameWords()), uint64_t(1) << 32);
}

TEST(MapHardening, InconsistentLayoutsAreRefusedAtLoadNamingTheFile)
{
  for (const char* name : {"divzero_min.map", "float_celllen_inconsistent.map", "layout_overflow_neg.map"})
  {
    const std::string path = repro(name);
    const std::string message = errorOf([&] { PlaceDatabase::load(path); });
    EXPECT_NE(message.find(path), std::string::npos) << name << ": " << message;
    EXPECT_NE(message.find("layout"), std::string::npos) << name << ": " << message;
  }
}

TEST(MapHardening, FrameMetricRefusesALayoutItWouldReadPast)
{
  DescriptorLayout floats;  // float_celllen_inconsistent.map's layout: 100000 floats in one word
  floats.binary = false;
  floats.cell_length = 100000;
  floats.cell_words = 1;
  EXPECT_THROW(FrameMetric{floats}, Error);
  EXPECT_THROW(PlaceDatabase{floats}, Error);
}

TEST(MapHardening, UnreadableStoredConfigurationIsAnOpenableError)
{
  // A list as a key of the stored configuration: refused by load, or at the latest by the parser.
  const std::string path = repro("config_seqkey.map");
  const std::string message = errorOf(
      [&]
      {
        const PlaceDatabase map = PlaceDatabase::load(path);
        Config::fromYamlString(map.configYaml());
      });
  EXPECT_NE(message.find("[a, b]"), std::string::npos) << message;
}

TEST(MapHardening, DeviceIsRefusedNotReadUntilMemoryRunsOut)
{
  const auto run = openable_test::runWithMemoryLimit(256 << 20, [] { PlaceDatabase::load("/dev/zero"); });
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kOpenableError) << run.message;
  EXPECT_NE(run.message.find("not a regular file"), std::string::npos) << run.message;
  EXPECT_NE(errorOf([] { PlaceDatabase::load(testing::TempDir()); }).find("not a regular file"), std::string::npos);
}

TEST(MapHardening, FrameCountIsBoundedByTheFileSizeBeforeAllocating)
{
  // 64 MiB of zeros claiming 8 M one-word frames: 8 bytes a frame of descriptor fit, but with their metadata
  // (93 bytes a frame) they do not. Refused within 256 MiB, not after allocating ~1 GB of FrameInfo.
  const uint64_t frames = 8u << 20;
  const std::string path = writeTemp("64mib.map", craftMap(64, 1, 0, frames, std::string(64u << 20, '\0')));
  const auto run = openable_test::runWithMemoryLimit(256 << 20, [&] { PlaceDatabase::load(path); });
  fs::remove(path);
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kOpenableError) << run.message;
  EXPECT_NE(run.message.find("frame count 8388608"), std::string::npos) << run.message;
}

TEST(MapHardening, MoreFramesThanTheCapacityAreRefused)
{
  // Two frames, capacity one: add() would later write past the storage it sized by the capacity.
  std::string payload;
  for (int frame = 0; frame < 2; ++frame)
  {
    put<uint64_t>(payload, frame);             // id
    put<double>(payload, 0.0);                 // stamp
    put<uint32_t>(payload, 0);                 // session
    payload.push_back('\0');                   // pose flag
    payload.append(7 * sizeof(double), '\0');  // pose
    put<uint64_t>(payload, 0);                 // source name: empty
  }
  payload.append(2 * sizeof(uint64_t), '\0');  // descriptors
  const std::string path = writeTemp("capacity.map", craftMap(64, 1, 1, 2, payload));
  const std::string message = errorOf([&] { PlaceDatabase::load(path); });
  EXPECT_NE(message.find("capacity"), std::string::npos) << message;
  // The same frames with room for them load.
  const std::string fine = writeTemp("capacity_ok.map", craftMap(64, 1, 2, 2, payload));
  EXPECT_EQ(PlaceDatabase::load(fine).size(), 2u);
}

TEST(MapHardening, NonFiniteFloatCellsAreAsFarAsCellsCanBe)
{
  // Found by fuzzing the map loader (test/fuzz/corpus/map_loader/found_float_nan_distance.map): a stored
  // float descriptor holding NaN reached a NaN -> uint32 conversion in FrameMetric.
  DescriptorLayout sift;
  sift.binary = false;
  sift.cell_length = 128;
  sift.cell_words = 64;
  std::vector<float> a(128, 0.0f), b(128, 0.0f);
  a[0] = 1.0f;
  b[0] = std::nanf("");
  uint64_t wa[64], wb[64];
  std::memcpy(wa, a.data(), sizeof(wa));
  std::memcpy(wb, b.data(), sizeof(wb));
  const FrameMetric metric(sift);
  EXPECT_EQ(metric.distance(wa, wb), kFloatScale);
  b[0] = INFINITY;
  std::memcpy(wb, b.data(), sizeof(wb));
  EXPECT_EQ(metric.distance(wa, wb), kFloatScale);
  EXPECT_EQ(metric.distance(wa, wa), 0u);
}
