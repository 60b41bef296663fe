#include "openable/io/image_source.h"

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
#include "openable/io/natural_order.h"

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
bool isJpeg(const std::string& bytes)
{
  return bytes.size() >= 3 && uint8_t(bytes[0]) == 0xFF && uint8_t(bytes[1]) == 0xD8 && uint8_t(bytes[2]) == 0xFF;
}

/// A JPEG ends its last scan (SOS, FF DA) with an end-of-image marker (FF D9). Inside a scan an FF byte is
/// always followed by 00 or a restart marker, so an FF D9 after the last SOS is the image's end; a file cut
/// short has none (libjpeg then warns "premature end" and fills the rest with grey). An EXIF thumbnail's own
/// markers come before the main image's last SOS.
bool jpegComplete(const std::string& bytes)
{
  const size_t sos = bytes.rfind("\xFF\xDA");
  if (sos == std::string::npos)
    return false;
  return bytes.find("\xFF\xD9", sos + 2) != std::string::npos;
}

/// The image of a file, or empty with `problem` saying why (unreadable, truncated JPEG, undecodable).
cv::Mat readImageFile(const std::string& path, std::string& problem)
{
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  problem.clear();
  if (bytes.empty())
    problem = "cannot read '" + path + "' (unreadable or empty)";
  else if (isJpeg(bytes) && !jpegComplete(bytes))
    problem = "'" + path + "' is a truncated JPEG (no end-of-image marker after its last scan); expected a "
              "complete file";
  if (!problem.empty())
    return cv::Mat();
  cv::Mat image = cv::imdecode(cv::Mat(1, int(bytes.size()), CV_8U, const_cast<char*>(bytes.data())), cv::IMREAD_COLOR);
  if (image.empty())
    problem = "cannot decode '" + path + "' as an image";
  return image;
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
    problem_.clear();
    if (video_->read >= video_->frames || !video_->capture.read(image) || image.empty())
      return false;
    name = "frame_" + std::to_string(video_->read++);
    return true;
  }
  if (next_index_ >= files_.size())
    return false;
  name = files_[next_index_++];
  const std::string file = (fs::path(path_) / name).string();
  image = readImageFile(file, problem_);
  return true;
}


}  // namespace openable
