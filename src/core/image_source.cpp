#include "openable/image_source.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "openable/error.h"
#include "openable/natural_order.h"

namespace fs = std::filesystem;

namespace openable
{
struct ImageSource::Video
{
  cv::VideoCapture capture;
  size_t frames = 0;
  size_t read = 0;
};

namespace
{
bool isImageFile(const fs::path& p)
{
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".ppm" || ext == ".pgm";
}
/// Frames of a video that really decode, by reading it to the end. Containers' frame counts
/// (CAP_PROP_FRAME_COUNT) are absent for raw streams (MJPEG: 0) and wrong for some files (an AVI header one
/// short), so callers that size arrays by size() would overrun or leave holes.
size_t countDecodableFrames(const std::string& path)
{
  cv::VideoCapture capture;
  if (!capture.open(path) || !capture.isOpened())
    throw Error("cannot open '" + path + "' as a video; expected a folder of images or a video file");
  size_t frames = 0;
  cv::Mat image;
  while (capture.read(image) && !image.empty())
    ++frames;
  return frames;
}
}  // namespace

ImageSource::ImageSource(const std::string& path) : path_(path)
{
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error("input '" + path + "' does not exist; expected a folder of images or a video file");
  if (fs::is_directory(path, ec))
  {
    for (const auto& entry : fs::directory_iterator(path, ec))
      if (entry.is_regular_file() && isImageFile(entry.path()))
        files_.push_back(entry.path().filename().string());
    // Natural order: `1.jpg, 2.jpg, ... 10.jpg` as named, not 1, 10, 11, ... 2 (plain string order).
    std::sort(files_.begin(), files_.end(), naturalLess);
    if (files_.empty())
      throw Error("folder '" + path + "' holds no images (.png .jpg .jpeg .bmp .ppm .pgm)");
    return;
  }
  video_ = std::make_unique<Video>();
  video_->frames = countDecodableFrames(path);
  if (video_->frames == 0)
    throw Error("video '" + path + "' has no frame that can be decoded");
  // The counting pass consumed the capture; reopen to stream from the first frame.
  if (!video_->capture.open(path) || !video_->capture.isOpened())
    throw Error("cannot reopen video '" + path + "' after counting its frames");
}

ImageSource::~ImageSource() = default;

size_t ImageSource::size() const
{
  return video_ ? video_->frames : files_.size();
}

bool ImageSource::isVideo() const
{
  return video_ != nullptr;
}

bool ImageSource::next(cv::Mat& image, std::string& name)
{
  if (video_)
  {
    // Never more than size(): callers allocate by it.
    if (video_->read >= video_->frames || !video_->capture.read(image) || image.empty())
      return false;
    name = "frame_" + std::to_string(video_->read++);
    return true;
  }
  if (next_index_ >= files_.size())
    return false;
  name = files_[next_index_++];
  image = cv::imread((fs::path(path_) / name).string(), cv::IMREAD_COLOR);
  return true;
}


}  // namespace openable
