#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace openable
{
/// A set of output files published together: each is written into a hidden folder inside `dir` and moved
/// into `dir` only by publish(), so a failed run leaves no partial set behind (and an earlier run's files
/// stay as they were). The hidden folder is removed on destruction, and so is `dir` when this created it
/// and nothing was published.
class StagedOutput
{
public:
  /// Creates `dir` when missing; throws Error when it cannot be created or written (now, not after minutes
  /// of work).
  explicit StagedOutput(const std::string& dir);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// Where to write the output file `name` before publish().
  std::string path(const std::string& name);
  /// Moves every file asked for with path() into `dir`.
  void publish();

private:
  std::filesystem::path dir_, staging_;
  std::vector<std::string> names_;
  bool created_ = false;
  bool published_ = false;
};

}  // namespace openable
