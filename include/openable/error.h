#pragma once

#include <stdexcept>
#include <string>

namespace openable
{
/// The one exception type of the core library. Its message always says what was wrong and what was
/// expected, so callers (the CLI, the nodelets) can log it as it is.
class Error : public std::runtime_error
{
public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace openable
