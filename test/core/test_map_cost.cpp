// Issue 22, finding 4: a map costs what its file holds. A few-kilobyte map that declares a 2^24-word
// (128 MB) frame layout and many sessions of 0 frames took `openable_map info` to 200 MB (one session) and
// more than 20 s (1,000 sessions): every empty session allocated one frame's worth of words. Crafted as
// ../shared/repro/make_many_empty_sessions_map.py writes them.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <string>

#include "crafted_maps.h"
#include "memory_limit.h"
#include "openable/error.h"
#include "openable/server/place_server.h"
#include "openable/map/session_map.h"

using namespace openable;

namespace
{
std::string writeTemp(const std::string& name, const std::string& bytes)
{
  const std::string path = testing::TempDir() + "/openable_test_map_cost_" + name;
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

double secondsToLoad(const std::string& path)
{
  const auto start = std::chrono::steady_clock::now();
  const SessionMap map = SessionMap::load(path);
  EXPECT_EQ(map.frameCount(), 0u);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

const size_t kHundredMegabytes = size_t(100) << 20;
}  // namespace

TEST(MapCost, OneEmptySessionWithAHugeLayoutCostsNoFrame)
{
  const std::string bytes = openable_test::emptySessionsMap(1);
  EXPECT_LT(bytes.size(), 200u);
  const std::string path = writeTemp("one.map", bytes);
  const openable_test::LimitedRun run =
      openable_test::runWithMemoryLimit(kHundredMegabytes, [&] { SessionMap::load(path).sessionCount(); });
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kReturned) << run.message;
  EXPECT_LT(secondsToLoad(path), 1.0);
}

TEST(MapCost, AThousandEmptySessionsLoadInProportionToTheFile)
{
  const std::string bytes = openable_test::emptySessionsMap(1000);
  EXPECT_LT(bytes.size(), 64u * 1024u);
  const std::string path = writeTemp("thousand.map", bytes);
  const openable_test::LimitedRun run =
      openable_test::runWithMemoryLimit(kHundredMegabytes,
                                        [&]
                                        {
                                          if (SessionMap::load(path).sessionCount() != 1000)
                                            throw Error("not 1000 sessions");
                                        });
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kReturned) << run.message;
  EXPECT_LT(secondsToLoad(path), 1.0);
}

TEST(MapCost, SessionsAndLayoutWordsAreCappedWithAClearMessage)
{
  const std::string many = writeTemp("many.map", openable_test::emptySessionsMap(20000, 1));
  try
  {
    SessionMap::load(many);
    ADD_FAILURE() << "20000 sessions loaded";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("declares 20000 sessions; at most 16384"), std::string::npos) << e.what();
  }
  const std::string wide =
      writeTemp("wide.map", openable_test::emptySessionsMap(1, 762601));  // 2^24 + 22 words a frame
  try
  {
    SessionMap::load(wide);
    ADD_FAILURE() << "a layout above 2^24 words loaded";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("words per frame; at most 16777216"), std::string::npos) << e.what();
  }
}

TEST(MapCost, ThePlaceServerRefusesSuchAMapWithinASecond)
{
  // ~load_map spent 9.2 s on 100 such sessions before refusing the map on its layout.
  const Config config = Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/gardens_point.yaml");
  const std::string path = writeTemp("server.map", openable_test::emptySessionsMap(1000, 762600, config.toYaml()));
  PlaceServer server(config);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(server.load(path), Error);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
  const openable_test::LimitedRun run =
      openable_test::runWithMemoryLimit(kHundredMegabytes, [&] { server.load(path); });
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kOpenableError) << run.message;
  EXPECT_NE(run.message.find("layout differs"), std::string::npos) << run.message;
  EXPECT_EQ(server.map().sessionCount(), 0u);
}
