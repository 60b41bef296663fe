#include "openable/staged_output.h"

#include <unistd.h>

#include "openable/error.h"

namespace fs = std::filesystem;

namespace openable
{
StagedOutput::StagedOutput(const std::string& dir) : dir_(dir)
{
  std::error_code ec;
  created_ = !fs::exists(dir_, ec);
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
  if (created_ && !published_)
    fs::remove(dir_, ec);  // only when empty: a folder this run created and never filled
}

std::string StagedOutput::path(const std::string& name)
{
  names_.push_back(name);
  return (staging_ / name).string();
}

void StagedOutput::publish()
{
  published_ = true;
  for (const auto& name : names_)
    fs::rename(staging_ / name, dir_ / name);
}

}  // namespace openable
