#include "evaluation/evaluation_text.h"

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

#include "openable/error.h"

namespace openable
{
namespace detail
{
std::string shapeText(int rows, int cols)
{
  return std::to_string(rows) + "x" + std::to_string(cols);
}

/// A double printed with up to 6 significant digits ("0.812", "1", "0.333333"): short for people, exact
/// enough for the plots and tables.
std::string numberText(double value)
{
  if (!std::isfinite(value))
  {
    return value > 0 ? "inf" : (value < 0 ? "-inf" : "nan");
  }
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

std::string jsonEscape(const std::string& text)
{
  std::string out;
  for (char c : text)
  {
    if (c == '"' || c == '\\')
    {
      out.push_back('\\');
      out.push_back(c);
    }
    else if (static_cast<unsigned char>(c) < 0x20)
    {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    }
    else
    {
      out.push_back(c);
    }
  }
  return out;
}

bool isCommentOrBlank(const std::string& line)
{
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

/// Parses `shape=RxC` from a comment line, as the published KITTI ground-truth files declare it.
bool parseDeclaredShape(const std::string& line, int& rows, int& cols)
{
  const size_t pos = line.find("shape=");
  if (pos == std::string::npos)
  {
    return false;
  }
  std::istringstream in(line.substr(pos + 6));
  char times = 0;
  long r = 0, c = 0;
  if (!(in >> r >> times >> c) || times != 'x' || r <= 0 || c <= 0 || r > INT32_MAX || c > INT32_MAX)
  {
    return false;
  }
  rows = static_cast<int>(r);
  cols = static_cast<int>(c);
  return true;
}

std::ifstream openText(const std::string& path, const std::string& what)
{
  std::ifstream in(path);
  if (!in)
  {
    throw Error(what + ": cannot open '" + path + "' (missing or unreadable)");
  }
  return in;
}

}  // namespace detail
}  // namespace openable
