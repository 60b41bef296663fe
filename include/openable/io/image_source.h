#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace openable
{
/// A sequence of images from a folder (png / jpg / jpeg / bmp / ppm / pgm, in natural order of file name:
/// numbers compare as numbers, so `image2.png` comes before `image10.png`; see naturalLess) or a video file.
class ImageSource
{
public:
  /// Throws Error when the path does not exist, holds no image, or the video cannot be opened or has no
  /// decodable frame. A video is decoded once here to count its frames (containers' counts are missing or
  /// wrong too often to size anything by), so opening costs one pass over the video.
  explicit ImageSource(const std::string& path);
  ~ImageSource();

  /// Frames in the source: image files of a folder, or frames of a video that decode. next() returns at
  /// most size() frames: exactly size() for a video, and for a folder size() entries of which unreadable
  /// files come as empty images.
  size_t size() const;
  bool isVideo() const;

  /// Reads the next frame into `image` and names it in `name` (file name, or "frame_N" for videos).
  /// Returns false at the end. An unreadable file gives an empty image with its name: the caller reports
  /// and skips it (problem() says why). A truncated JPEG (no end-of-image marker after its last scan),
  /// which a decoder would fill up with grey, is unreadable: it is not a frame.
  bool next(cv::Mat& image, std::string& name);
  /// Why the last next() gave an empty image ("" when it gave one).
  const std::string& problem() const
  {
    return problem_;
  }

  /// Image file names of a folder, in reading order (empty for a video).
  const std::vector<std::string>& files() const
  {
    return files_;
  }
  /// The first and last file name of a folder, so a tool can show which frames it reads and the user sees
  /// at once when the order is not the intended one ("" for a video).
  std::string firstFile() const
  {
    return files_.empty() ? std::string() : files_.front();
  }
  std::string lastFile() const
  {
    return files_.empty() ? std::string() : files_.back();
  }

private:
  std::string path_;
  std::vector<std::string> files_;
  size_t next_index_ = 0;
  std::string problem_;
  struct Video;
  std::unique_ptr<Video> video_;
};


}  // namespace openable
