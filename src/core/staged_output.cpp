#include "openable/staged_output.h"

#include <unistd.h>

#include "openable/error.h"

namespace fs = std::filesystem;

namespace openable
{
StagedOutput::StagedOutput(const std::string& dir) : dir_(dir)
{
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_))
    throw Error("cannot create output folder '" + dir + "'");
  staging_ = dir_ / (".openable_output." + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);
  if (!fs::create_directory(staging_, ec))
    throw Error("cannot write into output folder '" + dir + "'");
}

StagedOutput::~StagedOutput()
{
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

std::string StagedOutput::path(const std::string& name)
{
  names_.push_back(name);
  return (staging_ / name).string();
}

void StagedOutput::publish()
{
  for (const auto& name : names_)
    fs::rename(staging_ / name, dir_ / name);
}

}  // namespace openable
