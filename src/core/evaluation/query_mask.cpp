// Query masks: which query frames are evaluated (near-black frames left out).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "evaluation/evaluation_text.h"
#include "openable/io/atomic_file.h"
#include "openable/error.h"
#include "openable/evaluation/evaluation.h"
#include "openable/io/image_source.h"

namespace openable
{
using namespace detail;

// ---------------------------------------------------------------------------------------------------
// Query masks

std::vector<bool> brightFrameMask(const std::vector<cv::Mat>& images, double min_mean)
{
  std::vector<bool> mask;
  mask.reserve(images.size());
  for (size_t i = 0; i < images.size(); ++i)
  {
    if (images[i].empty())
    {
      throw Error("dark-frame mask: image " + std::to_string(i) + " is empty");
    }
    if (images[i].depth() != CV_8U && images[i].depth() != CV_16U)
    {
      throw Error("dark-frame mask: image " + std::to_string(i) + " is not 8-bit or 16-bit");
    }
    cv::Mat eight_bit = images[i];
    if (images[i].depth() == CV_16U)
    {
      images[i].convertTo(eight_bit, CV_8U, 1.0 / 257.0);  // the threshold is on the 8-bit scale
    }
    const cv::Scalar means = cv::mean(eight_bit);
    double mean = 0.0;
    for (int c = 0; c < eight_bit.channels(); ++c)
    {
      mean += means[c];
    }
    mask.push_back(mean / eight_bit.channels() >= min_mean);
  }
  return mask;
}

std::vector<bool> brightFrameMask(const std::string& image_source, double min_mean)
{
  ImageSource source(image_source);
  std::vector<bool> mask;
  cv::Mat image;
  std::string name;
  while (source.next(image, name))
  {
    if (image.empty())
    {
      throw Error("dark-frame mask: cannot read frame '" + name + "' of '" + image_source + "'");
    }
    mask.push_back(brightFrameMask(std::vector<cv::Mat>{image}, min_mean).front());
  }
  return mask;
}

std::vector<bool> loadQueryMask(const std::string& path)
{
  std::ifstream in = openText(path, "query mask");
  std::vector<bool> mask;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (isCommentOrBlank(line))
    {
      continue;
    }
    std::istringstream fields(line);
    std::string value, rest;
    fields >> value;
    if ((value != "0" && value != "1") || (fields >> rest))
    {
      throw Error("query mask: '" + path + "' line " + std::to_string(number) +
                  " is not 1 (evaluated) or 0 (left out): '" + line + "'");
    }
    mask.push_back(value == "1");
  }
  return mask;
}

void saveQueryMask(const std::string& path, const std::vector<bool>& mask)
{
  std::string text = "# one line per query: 1 = evaluated, 0 = left out\n";
  for (bool keep : mask)
  {
    text += keep ? "1\n" : "0\n";
  }
  writeFileAtomically(path, text);
}
}  // namespace openable
