#include "openable/io/staged_output.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "openable/io/atomic_file.h"
#include "openable/error.h"

namespace fs = std::filesystem;

namespace openable
{
namespace
{
const char kStaging[] = ".openable_staging.";
const char kCommit[] = ".openable_commit.";
const char kManifest[] = ".openable_set.";
const char kJournal[] = ".openable_journal";

/// The pid at the end of `name` ("<prefix>...<.pid>") when `name` starts with `prefix`, else -1.
long trailingPid(const std::string& name, const std::string& prefix)
{
  if (name.compare(0, prefix.size(), prefix) != 0)
    return -1;
  const size_t dot = name.rfind('.');
  return dot == std::string::npos || dot + 1 < prefix.size() ? -1 : pidSuffix(name, name.substr(0, dot + 1));
}

bool plainName(const std::string& name)
{
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos;
}

std::vector<std::string> readLines(const fs::path& path)
{
  std::vector<std::string> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (plainName(line))
      lines.push_back(line);
  return lines;
}

/// The names in folder `dir` (read first: the caller then moves them).
std::vector<std::string> entries(const fs::path& dir)
{
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    names.push_back(it->path().filename().string());
  return names;
}

fs::path parentOf(const fs::path& dir)
{
  return dir.has_parent_path() ? dir.parent_path() : fs::path(".");
}

void renameOrThrow(const fs::path& from, const fs::path& to)
{
  if (std::rename(from.c_str(), to.c_str()) != 0)
    throw Error("cannot move '" + from.string() + "' to '" + to.string() + "': " + std::strerror(errno));
}

/// Completes a committed journal folder `commit` of `dir`: moves its files in (the manifest last), removes the
/// earlier set's files the new set lacks, removes `commit`. Safe to repeat after a kill at any point.
void rollForward(const fs::path& commit, const fs::path& dir)
{
  std::string manifest;
  std::error_code ec;
  for (const std::string& name : entries(commit))
  {
    if (name == kJournal)
      continue;
    if (name.compare(0, sizeof(kManifest) - 1, kManifest) == 0)
      manifest = name;
    else
    {
      renameOrThrow(commit / name, dir / name);
      outputStep("set file moved");
    }
  }
  for (const std::string& name : readLines(commit / kJournal))
  {
    std::error_code ignored;
    fs::remove(dir / name, ignored);
    outputStep("earlier file removed");
  }
  if (!manifest.empty())
    renameOrThrow(commit / manifest, dir / manifest);
  syncPath(dir.string());
  outputStep("set moved");
  fs::remove_all(commit, ec);
}
}  // namespace

std::string StagedOutput::manifestName(const std::string& set)
{
  return kManifest + set;
}

void StagedOutput::recover(const std::string& dir_name)
{
  fs::path dir = fs::path(dir_name).lexically_normal();
  if (!dir.has_filename())
    dir = dir.parent_path();
  std::error_code ec;
  const std::string sibling = dir.filename().string() + kStaging;
  for (const std::string& name : entries(parentOf(dir)))
  {
    const long pid = trailingPid(name, sibling);
    if (pid > 0 && !processAlive(pid))
      fs::remove_all(parentOf(dir) / name, ec);  // staged (never exchanged) or the earlier set after the exchange
  }
  ec.clear();
  // Temporary files are removed only where a set of this folder owns their name: a user's file stays.
  std::set<std::string> owned;
  const std::vector<std::string> names = entries(dir);
  for (const std::string& name : names)
    if (name.compare(0, sizeof(kManifest) - 1, kManifest) == 0)
      for (const std::string& file : readLines(dir / name))
        owned.insert(file);
  for (const std::string& name : names)
  {
    const fs::path path = dir / name;
    long pid = -1;
    if ((pid = trailingPid(name, kStaging)) > 0 || (pid = pidSuffix(name, ".openable_output.")) > 0)
    {
      if (!processAlive(pid))
        fs::remove_all(path, ec);  // never committed: the earlier set stands
    }
    else if ((pid = trailingPid(name, kCommit)) > 0)
    {
      if (!processAlive(pid))
        rollForward(path, dir);  // committed: the new set stands
    }
    else if (name.find(".tmp.") != std::string::npos && owned.count(name.substr(0, name.rfind(".tmp."))))
    {
      pid = pidSuffix(name, name.substr(0, name.rfind(".tmp.") + 5));
      if (pid > 0 && !processAlive(pid))
        fs::remove(path, ec);
    }
    ec.clear();
  }
}

bool StagedOutput::ownsFolder() const
{
  std::error_code ec;
  if (fs::is_symlink(dir_, ec) || fs::equivalent(dir_, fs::current_path(ec), ec))
    return false;  // a link stays a link, the working folder stays in place: their files are replaced one by one
  const std::vector<std::string> earlier = readLines(dir_ / manifestName(set_));
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec))
  {
    const std::string name = it->path().filename().string();
    if (name != manifestName(set_) && std::find(earlier.begin(), earlier.end(), name) == earlier.end())
      return false;
  }
  return true;
}

StagedOutput::StagedOutput(const std::string& dir, const std::string& set)
    : dir_(fs::absolute(fs::path(dir)).lexically_normal()), set_(set)
{
  if (!dir_.has_filename())
    dir_ = dir_.parent_path();
  std::error_code ec;
  fs::create_directories(parentOf(dir_), ec);
  recover(dir_.string());
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw Error("cannot write into output folder '" + dir + "': it is a file");
  exchange_ = ownsFolder();  // missing, or nothing in it but this set's earlier files
  const std::string pid = std::to_string(::getpid());
  if (exchange_)
  {
    staging_ = parentOf(dir_) / (dir_.filename().string() + kStaging + pid);
    fs::remove_all(staging_, ec);
    exchange_ = fs::create_directory(staging_, ec);
  }
  if (!exchange_)
  {
    created_ = !fs::exists(dir_, ec);
    fs::create_directories(dir_, ec);
    if (!fs::is_directory(dir_, ec))
      throw Error("cannot create output folder '" + dir + "'");
    staging_ = dir_ / (kStaging + set_ + "." + pid);
    fs::remove_all(staging_, ec);
    if (!fs::create_directory(staging_, ec))
      throw Error("cannot write into output folder '" + dir + "'");
  }
}

StagedOutput::~StagedOutput()
{
  std::error_code ec;
  if (!staging_.empty())
    fs::remove_all(staging_, ec);
  if (created_ && !published_)
    fs::remove(dir_, ec);  // only when empty: a folder this run created and never filled
}

std::string StagedOutput::path(const std::string& name)
{
  if (!plainName(name) || name.compare(0, 9, ".openable") == 0)
    throw Error("output file name '" + name + "' is not a plain file name");
  if (std::find(names_.begin(), names_.end(), name) == names_.end())
    names_.push_back(name);
  return (staging_ / name).string();
}

void StagedOutput::publish()
{
  if (published_)
    return;
  for (const auto& name : names_)
    if (!fs::is_regular_file(staging_ / name))
      throw Error("output file '" + name + "' was never written");
  std::string manifest;
  for (const auto& name : names_)
    manifest += name + "\n";
  writeFileAtomically((staging_ / manifestName(set_)).string(), manifest);
  if (exchange_)
    publishByExchange();
  else
    publishByJournal();
}

void StagedOutput::publishByExchange()
{
  syncPath(staging_.string());
  outputStep("staging synced");
  const fs::path parent = parentOf(dir_);
  std::error_code ec;
  if (!fs::exists(dir_, ec))
  {
    renameOrThrow(staging_, dir_);  // nothing earlier: the new set appears whole
    published_ = true;
    staging_.clear();
    outputStep("set renamed");
    syncPath(parent.string());
    return;
  }
  const bool owned = ownsFolder();  // someone may have put a file into the folder while the set was made
  if (!owned || ::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) != 0)
  {
    if (owned && errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
      throw Error("cannot publish the output set in '" + dir_.string() + "': " + std::strerror(errno));
    // A shared folder now, or a file system without the exchange: the journal in the folder.
    const fs::path inside = dir_ / (kStaging + set_ + "." + std::to_string(::getpid()));
    renameOrThrow(staging_, inside);
    staging_ = inside;
    exchange_ = false;
    publishByJournal();
    return;
  }
  published_ = true;
  outputStep("set exchanged");
  syncPath(parent.string());
  // The earlier folder: anything in it that its set does not own (put there after the check above) moves
  // over to the new folder; the rest is the earlier set.
  const std::vector<std::string> earlier = readLines(staging_ / manifestName(set_));
  for (const std::string& name : entries(staging_))
    if (name != manifestName(set_) && std::find(earlier.begin(), earlier.end(), name) == earlier.end() &&
        !fs::exists(dir_ / name, ec))
      fs::rename(staging_ / name, dir_ / name, ec);
  fs::remove_all(staging_, ec);  // the earlier set
  staging_.clear();
  outputStep("earlier set removed");
}

void StagedOutput::publishByJournal()
{
  std::string journal;
  for (const std::string& name : readLines(dir_ / manifestName(set_)))
    if (std::find(names_.begin(), names_.end(), name) == names_.end())
      journal += name + "\n";
  writeFileAtomically((staging_ / kJournal).string(), journal);
  syncPath(staging_.string());
  outputStep("staging synced");
  const fs::path commit = dir_ / (kCommit + set_ + "." + std::to_string(::getpid()));
  renameOrThrow(staging_, commit);
  published_ = true;
  staging_.clear();
  syncPath(dir_.string());
  outputStep("journal committed");
  rollForward(commit, dir_);
}

}  // namespace openable
