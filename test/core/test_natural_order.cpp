// Natural order of file names (numbers as numbers) and the folder listing of ImageSource that uses it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "openable/io/image_source.h"
#include "openable/io/natural_order.h"
#include "test_util.h"

namespace fs = std::filesystem;
using openable::naturalLess;

TEST(NaturalOrder, NumbersCompareAsNumbers)
{
  EXPECT_TRUE(naturalLess("2.jpg", "10.jpg"));
  EXPECT_FALSE(naturalLess("10.jpg", "2.jpg"));
  EXPECT_TRUE(naturalLess("image2.png", "image10.png"));
  EXPECT_TRUE(naturalLess("frame_9_left.png", "frame_10_left.png"));
  EXPECT_TRUE(naturalLess("a9b100", "a10b2"));  // the first number decides
  EXPECT_TRUE(naturalLess("a10b2", "a10b100"));
}

TEST(NaturalOrder, TextComparesWithoutCaseAndPrefixesComeFirst)
{
  EXPECT_TRUE(naturalLess("apple", "Banana"));
  EXPECT_TRUE(naturalLess("Image", "image1"));
  EXPECT_TRUE(naturalLess("img", "img0"));
  EXPECT_TRUE(naturalLess("left.png", "left_1.png"));  // '.' < '_'
}

TEST(NaturalOrder, LongNumbersDoNotOverflowAndLeadingZerosTieBreakDeterministically)
{
  EXPECT_TRUE(naturalLess("x99999999999999999999999", "x100000000000000000000000"));
  EXPECT_TRUE(naturalLess("x1403715386762142976.png", "x1403715386812143104.png"));  // EuRoC stamps in ns
  // 007 and 7 are the same number: plain byte order decides, one way only.
  EXPECT_NE(naturalLess("img007.png", "img7.png"), naturalLess("img7.png", "img007.png"));
  EXPECT_NE(naturalLess("A.png", "a.png"), naturalLess("a.png", "A.png"));
  EXPECT_FALSE(naturalLess("same", "same"));
  EXPECT_TRUE(naturalLess("img1.png", "img01a.png"));  // the number is equal, then the shorter name
}

TEST(NaturalOrder, SortsUnpaddedAndPaddedNamesAsPeopleNameThem)
{
  std::vector<std::string> names, expected;
  for (int i = 1; i <= 120; ++i)
    expected.push_back(std::to_string(i) + ".jpg");
  names = expected;
  std::shuffle(names.begin(), names.end(), std::mt19937(7));
  std::sort(names.begin(), names.end(), naturalLess);
  EXPECT_EQ(names, expected);

  // Plain string order would give 1, 10, 100, 101, ...: the reason for this comparator.
  std::vector<std::string> plain = expected;
  std::sort(plain.begin(), plain.end());
  EXPECT_EQ(plain[1], "10.jpg");
}

TEST(NaturalOrder, IsAStrictWeakOrdering)
{
  const std::vector<std::string> names = {
      "a", "A", "a1", "a01",  "a001",  "a2",    "a10",   "b",       "B1",           "b01",
      "",  "1", "01", "x1y2", "x1y10", "x01y2", "x.png", "x_1.png", "Image007.jpg", "image7.jpg"};
  for (const auto& a : names)
  {
    EXPECT_FALSE(naturalLess(a, a)) << a;
    for (const auto& b : names)
    {
      if (a != b)
      {
        EXPECT_NE(naturalLess(a, b), naturalLess(b, a)) << a << " vs " << b;  // total on different names
      }
      for (const auto& c : names)
      {
        if (naturalLess(a, b) && naturalLess(b, c))
        {
          EXPECT_TRUE(naturalLess(a, c)) << a << " < " << b << " < " << c;
        }
      }
    }
  }
}

TEST(ImageSourceListing, FolderIsReadInNaturalOrderAndNamesItsEnds)
{
  const fs::path dir = fs::temp_directory_path() / ("openable_natural_order_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int i : {10, 2, 1, 11, 9, 100})
    fs::copy_file(openable_test::sharedData("gardens_point/day_right/Image000.jpg"),
                  dir / ("frame" + std::to_string(i) + ".jpg"));
  std::ofstream(dir / "notes.txt") << "not an image";
  const openable::ImageSource source(dir.string());
  const std::vector<std::string> expected = {"frame1.jpg",  "frame2.jpg",  "frame9.jpg",
                                             "frame10.jpg", "frame11.jpg", "frame100.jpg"};
  EXPECT_EQ(source.files(), expected);
  EXPECT_EQ(source.firstFile(), "frame1.jpg");
  EXPECT_EQ(source.lastFile(), "frame100.jpg");
  openable::ImageSource reader(dir.string());
  cv::Mat image;
  std::string name;
  std::vector<std::string> read;
  while (reader.next(image, name))
  {
    EXPECT_FALSE(image.empty()) << name;
    read.push_back(name);
  }
  EXPECT_EQ(read, expected);
  fs::remove_all(dir);
}
