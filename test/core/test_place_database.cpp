#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/map/place_database.h"
#include "openable/map/streamed_block.h"
#include "test_util.h"

using namespace openable;
namespace fs = std::filesystem;

namespace
{
DescriptorLayout layout22()
{
  DescriptorLayout l;
  l.binary = true;
  l.cell_length = 1386;
  l.cell_words = 22;
  return l;
}

std::string tempDir()
{
  const fs::path dir = fs::temp_directory_path() / ("openable_db_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir.string();
}

PlaceDatabase filled(size_t frames, size_t capacity = 0)
{
  std::mt19937_64 rng(1);
  PlaceDatabase db(layout22(), capacity, "descriptor: \"LDB\"\n");
  for (size_t i = 0; i < frames; ++i)
  {
    FrameInfo info;
    info.stamp = 100.0 + i * 0.1;
    info.session = 3;
    info.source = "Image" + std::to_string(i) + ".jpg";
    info.has_pose = i % 2 == 0;
    info.pose = {double(i), 2, 3, 0, 0, 0, 1};
    db.add(openable_test::randomWords(rng, 22), info);
  }
  return db;
}

std::string readAll(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeAll(const std::string& path, const std::string& bytes)
{
  std::ofstream(path, std::ios::binary).write(bytes.data(), long(bytes.size()));
}
}  // namespace

TEST(PlaceDatabase, StoresContiguousAlignedDescriptorsWithIds)
{
  const PlaceDatabase db = filled(100);
  ASSERT_EQ(db.size(), 100u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(db.data()) % 64, 0u);
  for (size_t i = 0; i < db.size(); ++i)
  {
    EXPECT_EQ(db.info(i).id, i);
    EXPECT_EQ(db.descriptor(i), db.data() + i * 22);
  }
  EXPECT_GE(db.bytes(), 100u * 22 * 8);
}

// A map past 32 MiB of descriptors is held on whole 2 MiB blocks (transparent huge pages where the kernel
// has them): still contiguous, and its descriptors survive growing past the reserve and shrinking.
TEST(PlaceDatabase, LargeMapsSitOnHugePageBlocksAndKeepTheirDescriptors)
{
  PlaceDatabase db(layout22());
  const size_t frames = (size_t(40) << 20) / (22 * 8);  // 40 MiB of descriptors
  db.reserve(frames);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(db.data()) % (size_t(2) << 20), 0u);
  std::mt19937_64 rng(5);
  std::vector<std::vector<uint64_t>> kept;
  for (size_t i = 0; i < frames + 10; ++i)  // past the reserve: the block grows and is copied
  {
    std::vector<uint64_t> d = openable_test::randomWords(rng, 22);
    if (i % 100000 == 0 || i + 3 >= frames + 10)
      kept.push_back(d);
    db.add(d);
  }
  db.shrinkToFit();
  EXPECT_EQ(reinterpret_cast<uintptr_t>(db.data()) % (size_t(2) << 20), 0u);
  ASSERT_EQ(db.size(), frames + 10);
  size_t k = 0;
  for (size_t i = 0; i < db.size(); ++i)
    if (i % 100000 == 0 || i + 3 >= frames + 10)
    {
      const std::vector<uint64_t> stored(db.descriptor(i), db.descriptor(i) + 22);
      ASSERT_EQ(stored, kept[k++]) << "frame " << i;
    }
}

TEST(PlaceDatabase, CapacityEvictsOldestFirstInBatches)
{
  PlaceDatabase db = filled(0, 64);
  std::mt19937_64 rng(2);
  for (int i = 0; i < 500; ++i)
  {
    db.add(openable_test::randomWords(rng, 22));
    ASSERT_LE(db.size(), 64u);
    ASSERT_EQ(db.info(db.size() - 1).id, uint64_t(i));
    ASSERT_EQ(db.info(0).id, db.firstId());
  }
  EXPECT_GE(db.size(), 60u);  // at least 15/16 of the capacity
  EXPECT_EQ(db.firstId() + db.size(), 500u);
}

TEST(PlaceDatabase, RejectsDescriptorOfWrongLength)
{
  PlaceDatabase db(layout22());
  EXPECT_THROW(db.add(std::vector<uint64_t>(21)), Error);
}

TEST(PlaceDatabase, SaveLoadRoundTripIsExact)
{
  const std::string path = tempDir() + "/map.bin";
  PlaceDatabase db = filled(0, 40);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 70; ++i)  // with evictions, so first id > 0
  {
    FrameInfo info;
    info.source = "f" + std::to_string(i);
    info.stamp = i;
    db.add(openable_test::randomWords(rng, 22), info);
  }
  db.save(path);
  const PlaceDatabase back = PlaceDatabase::load(path);
  EXPECT_EQ(back.layout(), db.layout());
  EXPECT_EQ(back.size(), db.size());
  EXPECT_EQ(back.firstId(), db.firstId());
  EXPECT_EQ(back.capacity(), db.capacity());
  EXPECT_EQ(back.configYaml(), db.configYaml());
  for (size_t i = 0; i < db.size(); ++i)
  {
    EXPECT_EQ(back.info(i).id, db.info(i).id);
    EXPECT_EQ(back.info(i).source, db.info(i).source);
    EXPECT_EQ(back.info(i).stamp, db.info(i).stamp);
    EXPECT_EQ(std::vector<uint64_t>(back.descriptor(i), back.descriptor(i) + 22),
              std::vector<uint64_t>(db.descriptor(i), db.descriptor(i) + 22));
  }
  for (const auto& entry : fs::directory_iterator(fs::path(path).parent_path()))
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << "temporary file left behind";
}

TEST(PlaceDatabase, CorruptTruncatedAndForeignFilesAreRefusedWithReasons)
{
  const std::string dir = tempDir();
  const std::string path = dir + "/good.bin";
  filled(10).save(path);
  const std::string good = readAll(path);

  auto expectRefused = [&](const std::string& bytes, const std::string& reason)
  {
    const std::string bad = dir + "/bad.bin";
    writeAll(bad, bytes);
    try
    {
      PlaceDatabase::load(bad);
      FAIL() << "accepted a bad map (" << reason << ")";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  expectRefused(flipped, "checksum");
  expectRefused(good.substr(0, good.size() - 100), "checksum");
  expectRefused(good.substr(0, 5), "not an openable_ros map");
  expectRefused("hello world, definitely not a map", "not an openable_ros map");
  std::string future = good;
  future[8] = 99;  // version field
  expectRefused(future, "version");
  EXPECT_THROW(PlaceDatabase::load(dir + "/missing.bin"), Error);
}

TEST(PlaceDatabase, SaveIntoUnwritableFolderFailsAndLeavesNothing)
{
  const PlaceDatabase db = filled(3);
  EXPECT_THROW(db.save("/nonexistent_folder/map.bin"), Error);
  const std::string dir = tempDir();
  const std::string path = dir + "/existing.bin";
  writeAll(path, "old");
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec);
  if (::geteuid() != 0)  // root ignores permissions; the missing-folder case above still ran
  {
    EXPECT_THROW(db.save(path), Error);
    EXPECT_EQ(readAll(path), "old");
  }
  fs::permissions(dir, fs::perms::owner_all);
}

// ---------------------------------------------------------------------------------------------------------
// Lean metadata (issue 11): a stored frame costs its descriptor plus at most 32 bytes.
TEST(SourceNames, EveryNameComesBackAfterAddingAndDropping)
{
  std::vector<std::string> names;
  for (int i = 0; i < 100; ++i)
    names.push_back("/data/gardens_point/day_right/Image" + std::to_string(1000 + i).substr(1) + ".jpg");
  names.push_back("");
  names.push_back("");
  names.push_back(std::string(300, 'x'));  // lengths above 127 take two varint bytes
  names.push_back(std::string(300, 'x') + "y");
  names.push_back("camera/image_raw");
  for (int i = 0; i < 40; ++i)
    names.push_back("camera/image_raw");  // one topic: nothing but the two length bytes
  SourceNames table;
  for (const auto& n : names)
    table.push_back(n);
  ASSERT_EQ(table.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i)
    EXPECT_EQ(table.at(i), names[i]) << i;
  EXPECT_THROW(table.at(names.size()), Error);
  table.dropOldest(37);
  names.erase(names.begin(), names.begin() + 37);
  ASSERT_EQ(table.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i)
    EXPECT_EQ(table.at(i), names[i]) << i;
  table.push_back("after");
  EXPECT_EQ(table.at(table.size() - 1), "after");
}

TEST(SourceNames, ConsecutiveFileNamesCostAFewBytes)
{
  SourceNames table;
  const int count = 1800;
  for (int i = 0; i < count; ++i)
    table.push_back("/work/shared/data/nordland/winter/images-" + std::to_string(100000 + (i + 1) * 10).substr(1) +
                    ".png");
  table.shrinkToFit();
  // Each name is 51 bytes; front-coded ~7, plus a whole name every 16.
  std::printf("[ measured ] %.1f bytes per name\n", double(table.bytes()) / count);
  EXPECT_LE(table.bytes(), size_t(12 * count));
}

TEST(PlaceDatabase, AFrameCostsItsDescriptorPlusAtMost32Bytes)
{
  DescriptorLayout hog_b;  // HOG-B: 324 bits in 6 words
  hog_b.cell_length = 324;
  hog_b.cell_words = 6;
  std::mt19937_64 rng(5);
  PlaceDatabase db(hog_b);
  const size_t frames = 1000;
  for (size_t i = 0; i < frames; ++i)
  {
    FrameInfo info;
    info.stamp = 1.5 * i;
    info.session = 2;
    info.source = "/work/shared/data/gardens_point/day_right/Image" + std::to_string(1000 + i).substr(1) + ".jpg";
    db.add(openable_test::randomWords(rng, 6), info);
  }
  db.shrinkToFit();
  const double metadata = double(db.bytes() - frames * 48) / frames;
  std::printf("[ measured ] %zu bytes for %zu frames: 48 of descriptor + %.1f of metadata per frame\n", db.bytes(),
              frames, metadata);
  EXPECT_LE(metadata, 32.0);
  EXPECT_EQ(db.info(999).source, "/work/shared/data/gardens_point/day_right/Image999.jpg");
  EXPECT_EQ(db.info(999).stamp, 1.5 * 999);
  EXPECT_EQ(db.info(999).id, 999u);
  EXPECT_FALSE(db.info(999).has_pose);
}

TEST(PlaceDatabase, PosesAndNamesFollowTheirFramesThroughEviction)
{
  PlaceDatabase db = filled(0, 32);  // every even frame has a pose {i, 2, 3, ...}
  std::mt19937_64 rng(9);
  for (size_t i = 0; i < 100; ++i)
  {
    FrameInfo info;
    info.source = "Image" + std::to_string(i) + ".jpg";
    info.has_pose = i % 2 == 0;
    info.pose = {double(i), 2, 3, 0, 0, 0, 1};
    info.stamp = double(i);
    db.add(openable_test::randomWords(rng, 22), info);
  }
  ASSERT_GT(db.firstId(), 0u);
  for (size_t position = 0; position < db.size(); ++position)
  {
    const FrameInfo info = db.info(position);
    EXPECT_EQ(info.source, "Image" + std::to_string(info.id) + ".jpg");
    EXPECT_EQ(info.stamp, double(info.id));
    EXPECT_EQ(info.has_pose, info.id % 2 == 0);
    if (info.has_pose)
    {
      EXPECT_EQ(info.pose[0], double(info.id));
    }
  }
  // And through a save and load.
  const std::string path = tempDir() + "/evicted.map";
  db.save(path);
  const PlaceDatabase back = PlaceDatabase::load(path);
  for (size_t position = 0; position < db.size(); ++position)
  {
    EXPECT_EQ(back.info(position).source, db.info(position).source);
    EXPECT_EQ(back.info(position).has_pose, db.info(position).has_pose);
    EXPECT_EQ(back.info(position).pose, db.info(position).pose);
    EXPECT_EQ(back.info(position).id, db.info(position).id);
  }
}

namespace
{
template <typename T>
void put(std::string& bytes, T value)
{
  bytes.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// A version 1 map, as builds before issue 11 wrote it: every frame with its id and a pose field.
std::string versionOneMap(uint64_t first_id, const std::vector<uint64_t>& ids)
{
  std::string bytes = "OPNABLEM";
  put<uint32_t>(bytes, 1);  // version
  put<uint32_t>(bytes, 1);  // binary
  put<int32_t>(bytes, 64);  // cell_length
  put<int32_t>(bytes, 1);   // cell_words
  put<int32_t>(bytes, 1);   // cells
  put<int32_t>(bytes, 1);   // blocks
  put<uint64_t>(bytes, 0);  // capacity
  put<uint64_t>(bytes, first_id);
  put<uint64_t>(bytes, ids.size());
  put<uint64_t>(bytes, 0);  // configuration: empty
  for (uint64_t id : ids)
  {
    put<uint64_t>(bytes, id);
    put<double>(bytes, 10.0 + double(id));  // stamp
    put<uint32_t>(bytes, 4);                // session
    put<uint8_t>(bytes, id % 2);            // pose flag
    for (int k = 0; k < 7; ++k)  // a position and the identity rotation (the input contract: unit quaternions)
      put<double>(bytes, k < 3 ? double(id + k) : k == 6 ? 1.0 : 0.0);
    const std::string source = "frame" + std::to_string(id);
    put<uint64_t>(bytes, source.size());
    bytes += source;
  }
  for (uint64_t id : ids)
    put<uint64_t>(bytes, id * 3);  // descriptors
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes)
  {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  put<uint64_t>(bytes, hash);
  return bytes;
}
}  // namespace

TEST(PlaceDatabase, VersionOneMapsLoadAndNonConsecutiveIdsAreRefused)
{
  const std::string path = tempDir() + "/version1.map";
  writeAll(path, versionOneMap(7, {7, 8, 9}));
  const PlaceDatabase db = PlaceDatabase::load(path);
  ASSERT_EQ(db.size(), 3u);
  EXPECT_EQ(db.firstId(), 7u);
  for (size_t i = 0; i < 3; ++i)
  {
    const FrameInfo info = db.info(i);
    EXPECT_EQ(info.id, 7 + i);
    EXPECT_EQ(info.stamp, 17.0 + i);
    EXPECT_EQ(info.session, 4u);
    EXPECT_EQ(info.source, "frame" + std::to_string(7 + i));
    EXPECT_EQ(info.has_pose, (7 + i) % 2 == 1);
    if (info.has_pose)
    {
      EXPECT_EQ(info.pose[2], double(7 + i + 2));
      EXPECT_EQ(info.pose[6], 1.0);
    }
    EXPECT_EQ(db.descriptor(i)[0], (7 + i) * 3);
  }
  // Saved again, it is a version 3 map (one session) with the same contents.
  db.save(path);
  EXPECT_EQ(readAll(path)[8], 3);
  EXPECT_EQ(PlaceDatabase::load(path).info(2).source, "frame9");

  writeAll(path, versionOneMap(7, {7, 9, 10}));
  try
  {
    PlaceDatabase::load(path);
    FAIL() << "accepted ids with a gap";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("not consecutive"), std::string::npos) << e.what();
  }
}

// The blocks every frame streams through: whole cache lines, and from 32 MiB on whole 2 MiB pages (the size a
// map's bytes() reports).
TEST(StreamedBlock, SmallBlocksAreCacheLineAlignedAndLargeOnesHugePageAligned)
{
  const size_t huge = size_t(2) << 20;
  for (size_t bytes :
       {size_t(1), size_t(100), size_t(4096), (size_t(32) << 20) - 64, size_t(32) << 20, (size_t(32) << 20) + 1})
  {
    void* block = openable::allocateStreamedBlock(bytes);
    ASSERT_NE(block, nullptr) << bytes;
    const size_t alignment = bytes < (size_t(32) << 20) ? 64 : huge;
    EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % alignment, 0u) << bytes;
    EXPECT_EQ(openable::streamedBlockBytes(bytes) % alignment, 0u) << bytes;
    EXPECT_GE(openable::streamedBlockBytes(bytes), bytes);
    EXPECT_LT(openable::streamedBlockBytes(bytes), bytes + alignment);
    static_cast<char*>(block)[bytes - 1] = 1;  // the whole block is there
    std::free(block);
  }
  EXPECT_EQ(openable::streamedBlockBytes((size_t(32) << 20) + 1), size_t(34) << 20);
}
