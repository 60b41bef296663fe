#include "openable/evaluation/loop_list.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "openable/error.h"
#include "openable/detection/loop_csv.h"

namespace openable
{
namespace
{
bool skippable(const std::string& line)
{
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

std::string lineError(const std::string& path, int number, const std::string& line, const std::string& expected)
{
  return "loop closures: '" + path + "' line " + std::to_string(number) + " is not " + expected + ": '" + line + "'";
}
}  // namespace

std::vector<LoopPair> loadLoopPairs(const std::string& path)
{
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error("loop closures: '" + path + "' is a folder; expected a file (loop_closures.csv, which "
                "openable_offline writes into its --output folder, or 'i j' pairs)");
  std::ifstream in(path);
  if (!in)
    throw Error("loop closures: cannot read '" + path + "'");
  std::vector<LoopPair> loops;
  enum class Format
  {
    kUnknown,
    kCsv,
    kPairs
  } format = Format::kUnknown;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    if (skippable(line))
      continue;
    if (format == Format::kUnknown)
    {
      const bool header = isLoopCsvHeader(line);
      format = header ? Format::kCsv : Format::kPairs;
      if (header)
        continue;
    }
    LoopPair loop;
    if (format == Format::kCsv)
    {
      if (!readLoopCsvPair(line, loop.query, loop.match))
        throw Error(lineError(path, number, line, "'query,match,...' with two frame indices >= 0"));
    }
    else
    {
      std::istringstream fields(line);
      long i = -1, j = -1;
      std::string rest;
      const bool parsed = static_cast<bool>(fields >> i >> j);
      if (!parsed || ((fields >> rest) && rest[0] != '#') || i < 0 || j < 0 || i > 2147483647L || j > 2147483647L)
        throw Error(lineError(path, number, line, "two frame indices 'i j' >= 0"));
      loop.query = static_cast<int>(i);
      loop.match = static_cast<int>(j);
    }
    loops.push_back(loop);
  }
  return loops;
}

void judgeLoops(std::vector<LoopPair>& loops, const GroundTruth& truth)
{
  for (LoopPair& loop : loops)
    loop.agrees = truth.isMatch(loop.query, loop.match) || truth.isMatch(loop.match, loop.query);
}

}  // namespace openable
