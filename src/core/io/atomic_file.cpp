#include "openable/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "openable/error.h"

namespace fs = std::filesystem;

namespace openable
{
namespace
{
OutputStepHook step_hook = nullptr;

std::string folderOf(const std::string& path)
{
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

/// Writes every byte to `fd`; false (errno set) when the disk is full or the write fails.
bool writeAll(int fd, const std::string& bytes)
{
  size_t done = 0;
  while (done < bytes.size())
  {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    done += static_cast<size_t>(n);
  }
  return true;
}
}  // namespace

void setOutputStepHook(OutputStepHook hook)
{
  step_hook = hook;
}

void outputStep(const char* step)
{
  if (step_hook)
    step_hook(step);
}

bool processAlive(long pid)
{
  if (pid <= 0)
    return false;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

long pidSuffix(const std::string& name, const std::string& prefix)
{
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0 || name.size() - prefix.size() > 9)
    return -1;
  long pid = 0;
  for (size_t i = prefix.size(); i < name.size(); ++i)
  {
    if (name[i] < '0' || name[i] > '9')
      return -1;
    pid = pid * 10 + (name[i] - '0');
  }
  return pid;
}

void syncPath(const std::string& path)
{
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw Error("cannot open '" + path + "' to sync it: " + std::strerror(errno));
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (result != 0 && error != EINVAL)  // EINVAL: a file system without fsync (nothing to make durable)
    throw Error("cannot sync '" + path + "' to disk: " + std::strerror(error));
}

std::string temporaryPath(const std::string& path)
{
  const std::string prefix = fs::path(path).filename().string() + ".tmp.";
  std::error_code ec;
  for (fs::directory_iterator it(folderOf(path), ec), end; !ec && it != end; it.increment(ec))
  {
    const long pid = pidSuffix(it->path().filename().string(), prefix);
    if (pid > 0 && !processAlive(pid))
    {
      std::error_code ignored;
      fs::remove(it->path(), ignored);  // a kill -9 during an earlier write of this file
    }
  }
  return path + ".tmp." + std::to_string(::getpid());
}

void publishFile(const std::string& temp, const std::string& path)
{
  try
  {
    syncPath(temp);
    outputStep("file synced");
  }
  catch (...)
  {
    std::remove(temp.c_str());
    throw;
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0)
  {
    const std::string reason = std::strerror(errno);
    std::remove(temp.c_str());
    throw Error("cannot move the new file into place at '" + path + "': " + reason);
  }
  outputStep("file renamed");
  syncPath(folderOf(path));
}

void writeFileAtomically(const std::string& path, const std::string& bytes)
{
  const std::string temp = temporaryPath(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
    throw Error("cannot write '" + path + "': " + std::strerror(errno));
  const bool written = writeAll(fd, bytes);
  const int error = errno;
  if (::close(fd) != 0 || !written)
  {
    std::remove(temp.c_str());
    throw Error("cannot write '" + path + "' (disk full?): " + std::strerror(written ? errno : error));
  }
  outputStep("file written");
  publishFile(temp, path);
}

}  // namespace openable
