// Replays the fuzz corpus (test/fuzz/corpus/<target>/: seeds, the repro files and every input that once
// found a bug) through the same entry functions as the libFuzzer targets, in the normal build: whatever
// the input, the loaders either accept it or throw openable::Error, which the entries swallow.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "../fuzz/fuzz_entries.h"

namespace fs = std::filesystem;

namespace
{
using Entry = std::function<void(const uint8_t*, size_t)>;

/// Every file of the target's corpus, sorted so failures are reported in a stable order.
std::vector<fs::path> corpus(const std::string& target)
{
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(std::string(OPENABLE_SOURCE_DIR) + "/test/fuzz/corpus/" + target))
    if (entry.is_regular_file())
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

void replay(const std::string& target, const Entry& entry)
{
  const std::vector<fs::path> files = corpus(target);
  ASSERT_FALSE(files.empty()) << "no corpus for " << target;
  for (const fs::path& file : files)
  {
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    try
    {
      entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    }
    catch (const std::exception& e)
    {
      ADD_FAILURE() << file.filename() << ": an exception other than openable::Error escaped: " << e.what();
    }
    catch (...)
    {
      ADD_FAILURE() << file.filename() << ": a non-standard exception escaped";
    }
  }
}
}  // namespace

TEST(FuzzCorpus, MapLoader)
{
  replay("map_loader", openable_fuzz::loadMap);
}

TEST(FuzzCorpus, ConfigYaml)
{
  replay("config_yaml", openable_fuzz::parseConfig);
}

TEST(FuzzCorpus, Npy)
{
  replay("npy", openable_fuzz::readNpy);
}

/// The real seeds (seed_*, written by write_seeds from data/sample) reach past the refusals: messages
/// stored by the server, frames processed by the detector; a seed refused at its first field would fuzz
/// nothing but the parser.
void expectSeedsGetThrough(const std::string& target, const std::function<size_t(const uint8_t*, size_t)>& entry)
{
  size_t seeds = 0;
  for (const fs::path& file : corpus(target))
  {
    if (file.filename().string().rfind("seed_", 0) != 0)
      continue;
    ++seeds;
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_GE(entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), 2u) << file.filename();
  }
  EXPECT_GE(seeds, 2u) << target;
}

TEST(FuzzCorpus, PlaceMessages)
{
  replay("place_messages", openable_fuzz::placeMessages);
  expectSeedsGetThrough("place_messages", openable_fuzz::placeMessages);
}

TEST(FuzzCorpus, DetectorImage)
{
  replay("detector_image", openable_fuzz::detectorFrames);
  expectSeedsGetThrough("detector_image", openable_fuzz::detectorFrames);
}
