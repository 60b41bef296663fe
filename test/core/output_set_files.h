#pragma once
// What an output folder holds, as a reader sees it: shared by the output-set tests (test_staged_output,
// test_output_sets).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

namespace openable_test
{
using Files = std::map<std::string, std::string>;

inline std::string readText(const std::filesystem::path& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// What a reader sees in `dir`: its files but the set's bookkeeping (".openable...") and `skip`.
inline Files visible(const std::filesystem::path& dir, const std::vector<std::string>& skip = {})
{
  Files files;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
  {
    const std::string name = it->path().filename().string();
    if (name.rfind(".openable", 0) != 0 && std::find(skip.begin(), skip.end(), name) == skip.end() &&
        std::filesystem::is_regular_file(it->path()))
      files[name] = readText(it->path());
  }
  return files;
}

/// Names in `dir` and beside it that only an unfinished run leaves.
inline std::vector<std::string> leftovers(const std::filesystem::path& dir)
{
  std::vector<std::string> found;
  std::error_code ec;
  for (const std::filesystem::path& folder : {dir, dir.parent_path()})
    for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    {
      const std::string name = it->path().filename().string();
      if (name.find(".openable_staging.") != std::string::npos || name.find(".openable_commit.") != std::string::npos ||
          name.find(".openable_output.") != std::string::npos || name.find(".tmp.") != std::string::npos)
        found.push_back(it->path().string());
    }
  return found;
}

}  // namespace openable_test
