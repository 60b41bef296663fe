#pragma once

// Runs a piece of code in a child process with a bounded address space, so a test can assert that a
// crafted input is refused before it allocates much, without the test process itself running out of
// memory when it is not (e.g. on an unfixed build).

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstddef>
#include <cstdio>
#include <fstream>
#include <functional>
#include <new>
#include <string>

#include "openable/error.h"

namespace openable_test
{
struct LimitedRun
{
  enum Outcome
  {
    kReturned,        ///< the action returned normally
    kOpenableError,   ///< it threw openable::Error (message holds what())
    kBadAlloc,        ///< it ran into the memory limit
    kOtherException,  ///< it threw anything else (message holds what() when known)
    kCrashed,         ///< the child died of a signal
  };
  Outcome outcome = kCrashed;
  std::string message;
};

/// Bytes of address space this process uses now (first field of /proc/self/statm, in pages).
inline size_t addressSpaceBytes()
{
  std::ifstream statm("/proc/self/statm");
  size_t pages = 0;
  statm >> pages;
  return pages * static_cast<size_t>(::sysconf(_SC_PAGESIZE));
}

/// Forks; the child may grow its address space by `extra_bytes` before allocations fail, runs `action`
/// and reports how it ended through a pipe.
inline LimitedRun runWithMemoryLimit(size_t extra_bytes, const std::function<void()>& action)
{
  LimitedRun run;
  int fds[2];
  if (::pipe(fds) != 0)
  {
    run.message = "pipe failed";
    return run;
  }
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0)
  {
    ::close(fds[0]);
    const rlimit limit{addressSpaceBytes() + extra_bytes, addressSpaceBytes() + extra_bytes};
    ::setrlimit(RLIMIT_AS, &limit);
    char code = LimitedRun::kReturned;
    std::string message;
    try
    {
      action();
    }
    catch (const openable::Error& e)
    {
      code = LimitedRun::kOpenableError;
      message = e.what();
    }
    catch (const std::bad_alloc& e)
    {
      code = LimitedRun::kBadAlloc;
      message = e.what();
    }
    catch (const std::exception& e)
    {
      code = LimitedRun::kOtherException;
      message = e.what();
    }
    catch (...)
    {
      code = LimitedRun::kOtherException;
    }
    const std::string report = std::string(1, code) + message;
    ssize_t ignored = ::write(fds[1], report.data(), report.size());
    (void)ignored;
    ::_exit(0);  // no gtest teardown, no atexit handlers of the parent's state
  }
  ::close(fds[1]);
  std::string report;
  char buffer[512];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof(buffer))) > 0;)
    report.append(buffer, static_cast<size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFEXITED(status) && !report.empty())
  {
    run.outcome = static_cast<LimitedRun::Outcome>(report[0]);
    run.message = report.substr(1);
  }
  return run;
}

}  // namespace openable_test
