// Loop closures from openable_offline's CSV or from 'i j' pair files, and their ground-truth verdict.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "openable/error.h"
#include "openable/evaluation/loop_list.h"

namespace fs = std::filesystem;

namespace
{
std::string writeFile(const std::string& name, const std::string& text)
{
  const fs::path path = fs::temp_directory_path() / ("openable_loop_list_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}
}  // namespace

TEST(LoopList, ReadsOfflineCsvIgnoringFurtherColumns)
{
  const auto loops = openable::loadLoopPairs(writeFile("a.csv", "query,match,distance\n120,3,0.25\n\n121,4,0.5\r\n"));
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].query, 120);
  EXPECT_EQ(loops[0].match, 3);
  EXPECT_EQ(loops[1].query, 121);
  EXPECT_EQ(loops[1].match, 4);
}

TEST(LoopList, ReadsPairFilesWithComments)
{
  const auto loops =
      openable::loadLoopPairs(writeFile("b.txt", "# shape=1101x1101\n829 0\n830 1  # a comment\n\n  831 2\n"));
  ASSERT_EQ(loops.size(), 3u);
  EXPECT_EQ(loops[2].query, 831);
  EXPECT_EQ(loops[2].match, 2);
}

TEST(LoopList, BadInputNamesFileAndLine)
{
  EXPECT_THROW(openable::loadLoopPairs("/nonexistent/loops.csv"), openable::Error);
  const struct
  {
    std::string text;
    std::string line;
  } cases[] = {{"query,match,distance\n1,2,0.1\nx,3,0.2\n", "line 3"},
               {"query,match\n1\n", "line 2"},
               {"query,match,distance\n-1,2,0.1\n", "line 2"},
               {"5 3\n5 three\n", "line 2"},
               {"5 3 7\n", "line 1"},
               {"5 -3\n", "line 1"}};
  for (const auto& c : cases)
  {
    try
    {
      openable::loadLoopPairs(writeFile("bad.txt", c.text));
      ADD_FAILURE() << "no error for " << c.text;
    }
    catch (const openable::Error& e)
    {
      EXPECT_NE(std::string(e.what()).find(c.line), std::string::npos) << e.what();
    }
  }
}

TEST(LoopList, JudgedAgainstTheGroundTruthInEitherDirection)
{
  // Frame 10 is the place of frame 2 (tolerance 1: 1..3 agree).
  std::vector<std::vector<int>> anchors(11);
  anchors[10] = {2};
  const openable::GroundTruth truth(anchors, 1, 11, 11, false, "test");
  std::vector<openable::LoopPair> loops = {{10, 2}, {10, 3}, {2, 10}, {10, 5}, {4, 2}};
  openable::judgeLoops(loops, truth);
  EXPECT_TRUE(loops[0].agrees);
  EXPECT_TRUE(loops[1].agrees);
  EXPECT_TRUE(loops[2].agrees);  // reported from the earlier end
  EXPECT_FALSE(loops[3].agrees);
  EXPECT_FALSE(loops[4].agrees);
}
