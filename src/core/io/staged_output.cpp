#include "openable/io/staged_output.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <unistd.h>

#include <algorithm>
#include <chrono>
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
const char kData[] = ".openable_data.";        // <dir>/.openable_data.<set>.<n>.<pid>: one set, whole
const char kCurrent[] = ".openable_current.";  // <dir>/.openable_current.<set>: the link to the set that counts
const char kManifest[] = ".openable_set.";

bool startsWith(const std::string& name, const std::string& prefix)
{
  return name.compare(0, prefix.size(), prefix) == 0;
}

/// The pid at the end of `name` ("<prefix>...<.pid>") when `name` starts with `prefix`, else -1.
long trailingPid(const std::string& name, const std::string& prefix)
{
  if (!startsWith(name, prefix))
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

/// A generation folder's name for `set`, unique even when a pid comes again: <kData><set>.<ns>.<pid>.
std::string generationName(const std::string& set)
{
  static long long last = 0;
  last = std::max(last + 1, static_cast<long long>(std::chrono::system_clock::now().time_since_epoch().count()));
  return kData + set + "." + std::to_string(last) + "." + std::to_string(::getpid());
}

/// Whether a leftover of process `pid` is stale: the process is gone, or it is this one (which has moved on).
bool staleOwner(long pid)
{
  return pid > 0 && (pid == ::getpid() || !processAlive(pid));
}

/// Where a file `name` of `set` in a shared folder points: through the set's current link, so that one rename
/// of that link switches every file of the set at once.
fs::path linkTarget(const std::string& set, const std::string& name)
{
  return fs::path(kCurrent + set) / name;
}

/// `link` made to point at `target`, atomically: a new link beside it renamed over it (a file or link).
void pointLink(const fs::path& link, const fs::path& target)
{
  const fs::path temp = link.string() + ".tmp." + std::to_string(::getpid());
  std::error_code ec;
  fs::remove(temp, ec);
  fs::create_symlink(target, temp, ec);
  if (ec)
    throw Error("cannot make the link '" + link.string() + "': " + ec.message());
  renameOrThrow(temp, link);
}

/// Whether `path` is a link of `set` (made by linkTarget) in a shared folder.
bool isSetLink(const fs::path& path, const std::string& set)
{
  std::error_code ec;
  return fs::is_symlink(path, ec) && startsWith(fs::read_symlink(path, ec).string(), kCurrent + set + "/");
}

/// The generation folder the current link of `set` in `dir` names ("" when there is none).
std::string currentData(const fs::path& dir, const std::string& set)
{
  std::error_code ec;
  const fs::path target = fs::read_symlink(dir / (kCurrent + set), ec);
  return ec ? std::string() : target.filename().string();
}

/// The sets of a shared folder: the names after kCurrent of its current links and after kData of its
/// generation folders (which end in ".<n>.<pid>").
std::set<std::string> sharedSets(const std::vector<std::string>& names)
{
  std::set<std::string> sets;
  for (const std::string& name : names)
    if (startsWith(name, kCurrent) && name.find(".tmp.") == std::string::npos)
      sets.insert(name.substr(sizeof(kCurrent) - 1));
    else if (startsWith(name, kData))
    {
      const std::string rest = name.substr(sizeof(kData) - 1);
      const size_t pid_dot = rest.rfind('.');
      const size_t n_dot = pid_dot == std::string::npos || pid_dot == 0 ? std::string::npos : rest.rfind('.', pid_dot - 1);
      if (n_dot != std::string::npos && n_dot > 0)
        sets.insert(rest.substr(0, n_dot));
    }
  return sets;
}

/// Settles set `set` of shared folder `dir` after dead runs: removes its generation folders that are not
/// current (their writer died before or after the switch), its links that the current set lacks (made for a
/// switch that never came, or left by one that did) and its links' temporaries.
void settleShared(const fs::path& dir, const std::string& set)
{
  const std::string current = currentData(dir, set);
  const std::vector<std::string> owned = readLines(dir / (kCurrent + set) / (kManifest + set));
  const std::vector<std::string> names = entries(dir);
  const std::string data = kData + set + ".";
  // A live writer has made its links before its switch: they point at nothing yet and must stay.
  bool writer_alive = false;
  for (const std::string& name : names)
    writer_alive = writer_alive || (startsWith(name, data) && name != current && !staleOwner(trailingPid(name, kData)));
  std::error_code ec;
  for (const std::string& name : names)
  {
    const fs::path path = dir / name;
    const size_t temp = name.rfind(".tmp.");
    if (startsWith(name, data) && name != current && staleOwner(trailingPid(name, kData)))
      fs::remove_all(path, ec);
    else if (temp != std::string::npos && fs::is_symlink(path, ec) &&
             staleOwner(pidSuffix(name, name.substr(0, temp + 5))) &&
             (isSetLink(path, set) || startsWith(fs::read_symlink(path, ec).string(), data)))
      fs::remove(path, ec);  // a link's temporary (pointLink)
    else if (!writer_alive && isSetLink(path, set) && !fs::exists(path, ec) && name != kManifest + set &&
             std::find(owned.begin(), owned.end(), name) == owned.end())
      fs::remove(path, ec);
    else
      continue;
    outputStep("stale entry removed");
    ec.clear();
  }
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
    if (startsWith(name, kManifest))
      for (const std::string& file : readLines(dir / name))
        owned.insert(file);
  for (const std::string& name : names)
  {
    const fs::path path = dir / name;
    long pid = -1;
    if ((pid = trailingPid(name, kStaging)) > 0 || (pid = pidSuffix(name, ".openable_output.")) > 0)
    {
      if (!processAlive(pid))
        fs::remove_all(path, ec);  // never published: the earlier set stands
    }
    else if (name.find(".tmp.") != std::string::npos && owned.count(name.substr(0, name.rfind(".tmp."))))
    {
      pid = pidSuffix(name, name.substr(0, name.rfind(".tmp.") + 5));
      if (pid > 0 && !processAlive(pid))
        fs::remove(path, ec);
    }
    ec.clear();
  }
  for (const std::string& set : sharedSets(names))
    settleShared(dir, set);
}

bool StagedOutput::ownsFolder() const
{
  std::error_code ec;
  if (fs::is_symlink(dir_, ec) || fs::equivalent(dir_, fs::current_path(ec), ec))
    return false;  // a link stays a link, the working folder stays in place: the set goes in as its links
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
  if (!plainName(name) || startsWith(name, ".openable"))
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
    publishShared();
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
    // A shared folder now, or a file system without the exchange: the set's links in the folder.
    const fs::path inside = dir_ / (kStaging + set_ + "." + std::to_string(::getpid()));
    renameOrThrow(staging_, inside);
    staging_ = inside;
    exchange_ = false;
    publishShared();
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

void StagedOutput::publishShared()
{
  syncPath(staging_.string());
  outputStep("staging synced");
  // Every file of the set is a link through the set's current link (<name> -> .openable_current.<set>/<name>,
  // which points at a generation folder), so one rename of the current link switches the whole set.
  const std::string manifest = manifestName(set_);
  const std::vector<std::string> earlier = readLines(dir_ / manifest);
  linkEarlierSet(earlier);
  const std::string data = generationName(set_);
  renameOrThrow(staging_, dir_ / data);
  staging_.clear();
  outputStep("generation ready");
  // Links the earlier set lacks point at nothing until the switch: the name is absent, as it was.
  std::vector<std::string> replaced;  // files of that name that are not the set's links: replaced after
  std::error_code ec;
  for (const std::string& name : names_)
  {
    const fs::path path = dir_ / name;
    if (isSetLink(path, set_))
      continue;
    if (fs::exists(fs::symlink_status(path, ec)))
      replaced.push_back(name);
    else
    {
      fs::create_symlink(linkTarget(set_, name), path, ec);
      if (ec)
        throw Error("cannot make the link '" + path.string() + "': " + ec.message());
    }
  }
  if (!isSetLink(dir_ / manifest, set_))
    pointLink(dir_ / manifest, linkTarget(set_, manifest));
  syncPath(dir_.string());
  outputStep("links made");
  pointLink(dir_ / (kCurrent + set_), data);  // the switch: the new set is the one that counts
  published_ = true;
  syncPath(dir_.string());
  outputStep("set switched");
  for (const std::string& name : replaced)
    pointLink(dir_ / name, linkTarget(set_, name));
  for (const std::string& name : earlier)
    if (std::find(names_.begin(), names_.end(), name) == names_.end() && isSetLink(dir_ / name, set_))
      fs::remove(dir_ / name, ec);
  outputStep("earlier links removed");
  settleShared(dir_, set_);  // the earlier generation
  outputStep("earlier set removed");
}

void StagedOutput::linkEarlierSet(const std::vector<std::string>& earlier)
{
  // The earlier set as plain files (written into a folder it owned, or by an earlier version): hard links of
  // them in a generation folder of their own, then each file replaced by its link, the same bytes before and
  // after whenever a kill comes (the next run goes on from where it stopped).
  const std::string manifest = manifestName(set_);
  std::error_code ec;
  std::vector<std::string> files;
  for (const std::string& name : earlier)
    if (fs::is_regular_file(fs::symlink_status(dir_ / name, ec)))
      files.push_back(name);
  if (fs::is_regular_file(fs::symlink_status(dir_ / manifest, ec)))
    files.push_back(manifest);
  if (files.empty())
    return;
  if (currentData(dir_, set_).empty())
  {
    const fs::path data = dir_ / generationName(set_);
    fs::create_directory(data, ec);
    for (const std::string& name : files)
    {
      fs::create_hard_link(dir_ / name, data / name, ec);
      if (ec)
        fs::copy_file(dir_ / name, data / name, ec);
      if (ec)
        throw Error("cannot keep the earlier '" + (dir_ / name).string() + "': " + ec.message());
    }
    syncPath(data.string());
    pointLink(dir_ / (kCurrent + set_), data.filename());
    outputStep("earlier set linked");
  }
  for (const std::string& name : files)
    if (fs::exists(dir_ / (kCurrent + set_) / name, ec))
      pointLink(dir_ / name, linkTarget(set_, name));
  syncPath(dir_.string());
}

}  // namespace openable
