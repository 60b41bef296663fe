#pragma once
// Writing an output set and killing the writer at one of its steps: shared by the output-set tests of the core
// (test_staged_output, test_staged_output_shared).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

#include "openable/io/atomic_file.h"
#include "openable/io/staged_output.h"
#include "output_set_files.h"

namespace openable_test
{
inline const Files kOld = {{"a.csv", "old a\n"}, {"b.png", std::string(3000, 'o')}, {"only_old.txt", "old\n"}};
inline const Files kNew = {{"a.csv", "new a\n"}, {"b.png", std::string(5000, 'n')}, {"only_new.txt", "new\n"}};

/// `files` written as the output set `set` of `dir` (StagedOutput: staged, then published).
inline void writeSet(const std::filesystem::path& dir, const Files& files, const std::string& set = "test_set")
{
  openable::StagedOutput output(dir.string(), set);
  for (const auto& [name, text] : files)
    openable::writeFileAtomically(output.path(name), text);
  output.publish();
}

/// Runs `work` in a child process killed (SIGKILL) at its `step`-th output step; true when it was killed, false
/// when it finished first.
inline bool killedAt(int step, const std::function<void()>& work)
{
  static int kill_at = 0;
  const pid_t child = ::fork();
  if (child == 0)
  {
    kill_at = step;
    openable::setOutputStepHook(
        [](const char*)
        {
          if (--kill_at == 0)
            ::raise(SIGKILL);
        });
    try
    {
      work();
    }
    catch (...)
    {
      ::_exit(3);
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0)) << "step " << step;
  return WIFSIGNALED(status);
}

}  // namespace openable_test
