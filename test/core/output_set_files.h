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

/// Names in `dir` and beside it that only an unfinished run leaves: staging folders, temporaries, generation
/// folders of a shared folder that its set's current link does not name, links that point at nothing.
inline std::vector<std::string> leftovers(const std::filesystem::path& dir)
{
  std::vector<std::string> found;
  std::error_code ec;
  for (const std::filesystem::path& folder : {dir, dir.parent_path()})
    for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    {
      const std::string name = it->path().filename().string();
      std::error_code status;
      bool stale = name.find(".openable_staging.") != std::string::npos ||
                   name.find(".openable_output.") != std::string::npos || name.find(".tmp.") != std::string::npos ||
                   (std::filesystem::is_symlink(it->path(), status) && !std::filesystem::exists(it->path(), status));
      const std::string data = ".openable_data.";
      if (folder == dir && name.rfind(data, 0) == 0)
      {
        // .openable_data.<set>.<n>.<pid>: stale unless .openable_current.<set> names it.
        const std::string rest = name.substr(data.size());
        const size_t pid_dot = rest.rfind('.');
        const std::string set = rest.substr(0, rest.rfind('.', pid_dot - 1));
        stale = stale || std::filesystem::read_symlink(dir / (".openable_current." + set), status).string() != name;
      }
      if (stale)
        found.push_back(it->path().string());
    }
  return found;
}

}  // namespace openable_test
