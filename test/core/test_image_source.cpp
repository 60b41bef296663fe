// Issue 9 (hardening): ImageSource::size() of a video is the number of frames next() really returns, not
// the container's claim (absent for a raw MJPEG stream, one short in undercount.avi), so callers can size
// their arrays by it.
#include <gtest/gtest.h>

#include <string>

#include "openable/error.h"
#include "openable/io/image_source.h"

namespace
{
std::string repro(const std::string& name)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/test/data/repro/" + name;
}

size_t framesReturned(openable::ImageSource& source)
{
  size_t frames = 0;
  cv::Mat image;
  std::string name;
  while (source.next(image, name))
  {
    EXPECT_FALSE(image.empty()) << name;
    EXPECT_EQ(name, "frame_" + std::to_string(frames));
    ++frames;
  }
  return frames;
}
}  // namespace

TEST(ImageSource, RawMjpegStreamWithoutFrameCountHasItsTenFrames)
{
  openable::ImageSource source(repro("gp10.mjpeg"));
  ASSERT_TRUE(source.isVideo());
  EXPECT_EQ(source.size(), 10u);
  EXPECT_EQ(framesReturned(source), source.size());
}

TEST(ImageSource, UnderReportedAviCountsWhatDecodes)
{
  // Its header says 3 frames; 4 decode.
  openable::ImageSource source(repro("undercount.avi"));
  EXPECT_EQ(source.size(), 4u);
  EXPECT_EQ(framesReturned(source), source.size());
}
