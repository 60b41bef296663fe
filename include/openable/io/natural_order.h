#pragma once

#include <string>

namespace openable
{
/// Natural ("human") order of file names: runs of digits compare as numbers, so `image2.png` comes before
/// `image10.png` and `1.jpg, 2.jpg, ... 10.jpg` keep the order their author meant. Letters compare without
/// regard to case. Names equal under these rules (`img01` and `img1`, `A.png` and `a.png`) fall back to
/// plain byte order, so this is a strict weak ordering fit for std::sort and any two different names have
/// a fixed order.
bool naturalLess(const std::string& a, const std::string& b);

}  // namespace openable
