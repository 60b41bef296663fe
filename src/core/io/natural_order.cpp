#include "openable/io/natural_order.h"

#include <cctype>
#include <cstddef>

namespace openable
{
namespace
{
bool isDigit(char c)
{
  return std::isdigit(static_cast<unsigned char>(c)) != 0;
}

char folded(char c)
{
  return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
}

/// -1, 0 or 1 as the digit runs a[i..i_end) and b[j..j_end) compare as numbers. Compared as text after
/// the leading zeros (longer is larger, then digit by digit), so a run of any length never overflows.
int compareNumbers(const std::string& a, size_t i, size_t i_end, const std::string& b, size_t j, size_t j_end)
{
  while (i < i_end && a[i] == '0')
    ++i;
  while (j < j_end && b[j] == '0')
    ++j;
  if (i_end - i != j_end - j)
    return i_end - i < j_end - j ? -1 : 1;
  for (; i < i_end; ++i, ++j)
  {
    if (a[i] != b[j])
      return a[i] < b[j] ? -1 : 1;
  }
  return 0;
}
}  // namespace

bool naturalLess(const std::string& a, const std::string& b)
{
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size())
  {
    if (isDigit(a[i]) && isDigit(b[j]))
    {
      size_t i_end = i, j_end = j;
      while (i_end < a.size() && isDigit(a[i_end]))
        ++i_end;
      while (j_end < b.size() && isDigit(b[j_end]))
        ++j_end;
      const int order = compareNumbers(a, i, i_end, b, j, j_end);
      if (order != 0)
        return order < 0;
      i = i_end;
      j = j_end;
      continue;
    }
    const char x = folded(a[i]), y = folded(b[j]);
    if (x != y)
      return x < y;
    ++i;
    ++j;
  }
  if (i < a.size() || j < b.size())
    return j < b.size();  // the one that ended first is a prefix: it comes first
  // Equal for a reader (leading zeros, case): any fixed order keeps the sort deterministic.
  return a < b;
}

}  // namespace openable
