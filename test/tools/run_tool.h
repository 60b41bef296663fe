#pragma once
// Runs a program as a user would, from the tool tests: its exit code and everything it printed.

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace openable_test
{
struct Result
{
  int exit_code;
  std::string output;  // stdout and stderr
};

/// `binary arguments 2>&1`; exit_code -1 when it could not run or ended by a signal.
inline Result runTool(const std::string& binary, const std::string& arguments)
{
  const std::string command = binary + " " + arguments + " 2>&1";
  Result r{-1, ""};
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe)
    return r;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof(buffer), pipe))
    r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}
}  // namespace openable_test
