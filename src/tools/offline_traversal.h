#pragma once
// openable_offline's reading side: a traversal frame by frame, timed, and frames that fail reported and
// skipped.

#include <chrono>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "openable/error.h"
#include "openable/io/image_source.h"
#include "openable/detection/online_detector.h"

namespace offline
{
using openable::Error;

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Timings
{
  double read = 0, preprocess = 0, describe = 0, match = 0;
  size_t frames = 0;
};

/// Reads a traversal (and its right images in stereo mode) frame by frame. Frames are counted as they are
/// decoded: a video container's frame count is never trusted.
class TraversalReader
{
public:
  TraversalReader(const std::string& path, const std::string& right_path, bool quiet) : source_(path)
  {
    if (!quiet)
      std::cerr << "reading " << path << ": " << source_.size() << " frames"
                << (source_.isVideo() ? "" : " (" + source_.firstFile() + " .. " + source_.lastFile() + ")") << "\n";
    if (!right_path.empty())
    {
      right_ = std::make_unique<openable::ImageSource>(right_path);
      if (!source_.isVideo() && !right_->isVideo() && right_->size() != source_.size())
        throw Error("left '" + path + "' has " + std::to_string(source_.size()) + " frames but right '" + right_path +
                    "' has " + std::to_string(right_->size()));
    }
  }

  size_t size() const
  {
    return source_.size();
  }
  /// A video's size() is its container's word, not a count of decodable frames.
  bool isVideo() const
  {
    return source_.isVideo();
  }

  /// The next frame's images into `input` (empty when unreadable); false at the end.
  bool next(openable::FrameInput& input, Timings& t)
  {
    const auto start = Clock::now();
    input = openable::FrameInput();
    if (!source_.next(input.image, input.source))
      return false;
    if (!source_.problem().empty())  // the frame is then skipped as empty: say why first
      std::cerr << "warning: " << source_.problem() << "\n";
    std::string right_name;
    if (right_ && !right_->next(input.right, right_name))
      throw Error("the right images end before the left ones at '" + input.source + "'");
    t.read += msSince(start);
    return true;
  }

private:
  openable::ImageSource source_;
  std::unique_ptr<openable::ImageSource> right_;
};

/// Describes or processes one frame; an unreadable or undescribable frame is reported and skipped.
template <typename Step>
bool tryFrame(const std::string& name, Step step)
{
  try
  {
    step();
    return true;
  }
  catch (const Error& e)
  {
    std::cerr << "warning: skipping " << name << ": " << e.what() << "\n";
  }
  catch (const cv::Exception& e)
  {
    std::cerr << "warning: skipping " << name << ": " << e.what() << "\n";
  }
  return false;
}

}  // namespace offline
