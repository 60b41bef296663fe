// openable_offline reads a folder of unpadded numeric names (1.jpg, 2.jpg, ... 15.jpg) in the order they
// were named: its distance matrix equals the one of the same frames named with padded numbers
// (01.jpg ... 15.jpg), whose plain string order is already right. With plain string order the unpadded
// folder would be read 1, 10, 11, ..., 15, 2, ... and the matrices would differ.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "openable/io/npy.h"
#include "../core/test_util.h"

#ifndef OPENABLE_OFFLINE_BINARY
#error "OPENABLE_OFFLINE_BINARY (path of the openable_offline executable) must be defined by the build"
#endif

namespace fs = std::filesystem;

namespace
{
const int kFrames = 15;  // crosses 9 -> 10, where string order and natural order part

int runOffline(const std::string& input, const std::string& output)
{
  const std::string command = std::string("'") + OPENABLE_OFFLINE_BINARY + "' --config '" + OPENABLE_SOURCE_DIR +
                              "/config/paper.yaml' --reference '" + input + "' --output '" + output +
                              "' --set sequence_length=2 --set exclusion_window=2 >'" + output + ".log' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Equal shape and cells, NaN equal to NaN; counts the finite cells.
::testing::AssertionResult sameMatrix(const cv::Mat& a, const cv::Mat& b, int& finite)
{
  if (a.size() != b.size() || a.type() != b.type() || a.type() != CV_32F)
    return ::testing::AssertionFailure() << "shapes or types differ";
  finite = 0;
  for (int r = 0; r < a.rows; ++r)
  {
    for (int c = 0; c < a.cols; ++c)
    {
      const float x = a.at<float>(r, c), y = b.at<float>(r, c);
      if (std::isnan(x) != std::isnan(y) || (!std::isnan(x) && x != y))
        return ::testing::AssertionFailure() << "cell (" << r << ", " << c << "): " << x << " vs " << y;
      finite += std::isnan(x) ? 0 : 1;
    }
  }
  return ::testing::AssertionSuccess();
}
}  // namespace

TEST(OfflineNaturalOrder, UnpaddedNamesGiveTheMatrixOfPaddedNames)
{
  const fs::path root = fs::temp_directory_path() / ("openable_offline_natural_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "unpadded");
  fs::create_directories(root / "padded");
  for (int i = 1; i <= kFrames; ++i)
  {
    // Real frames, each a different place of the Gardens Point walk (every 4th image).
    char source[64], padded[16];
    std::snprintf(source, sizeof(source), "gardens_point/day_right/Image%03d.jpg", 4 * i);
    std::snprintf(padded, sizeof(padded), "%02d.jpg", i);
    fs::copy_file(openable_test::sharedData(source), root / "unpadded" / (std::to_string(i) + ".jpg"));
    fs::copy_file(openable_test::sharedData(source), root / "padded" / padded);
  }
  ASSERT_EQ(runOffline((root / "unpadded").string(), (root / "out_unpadded").string()), 0)
      << "see " << (root / "out_unpadded.log");
  ASSERT_EQ(runOffline((root / "padded").string(), (root / "out_padded").string()), 0)
      << "see " << (root / "out_padded.log");
  const cv::Mat unpadded = openable::readNpy((root / "out_unpadded" / "distance_matrix.npy").string());
  const cv::Mat padded = openable::readNpy((root / "out_padded" / "distance_matrix.npy").string());
  ASSERT_EQ(unpadded.rows, kFrames);
  int finite = 0;
  EXPECT_TRUE(sameMatrix(unpadded, padded, finite));
  // Enough compared cells that a reordering of frames would show (78 of 225 measured: frames without a
  // full sequence of 2 or inside the exclusion window compare nothing).
  EXPECT_GE(finite, kFrames * 3);
  fs::remove_all(root);
}
