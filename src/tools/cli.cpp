#include "cli.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "openable/config.h"

namespace openable
{
namespace cli
{
namespace
{
/// A bound as people write it: whole numbers in full (1000000), others with 6 significant digits (3.14159).
std::string bound(double value)
{
  char text[32];
  if (value == std::floor(value) && std::fabs(value) < 1e15)
    std::snprintf(text, sizeof(text), "%.0f", value);
  else
    std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

[[noreturn]] void refuse(const std::string& option, const std::string& text, const std::string& expected,
                         const std::string& note)
{
  throw UsageError(option + ": '" + text + "' is not allowed; expected " + expected +
                   (note.empty() ? "" : " (" + note + ")"));
}
}  // namespace

std::optional<long long> toInteger(const std::string& text)
{
  // from_chars takes no leading space or '+', and reports a value that does not fit.
  long long value = 0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value, 10);
  if (text.empty() || error != std::errc() || stop != end)
    return std::nullopt;
  return value;
}

std::optional<double> toNumber(const std::string& text)
{
  // Decimal and scientific notation only: no hex, and nan or inf are refused below.
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value, std::chars_format::general);
  if (text.empty() || error != std::errc() || stop != end || !std::isfinite(value))
    return std::nullopt;
  return value + 0.0;  // -0 is 0
}

long long parseInteger(const std::string& option, const std::string& text, long long low, long long high,
                       const std::string& note)
{
  const std::optional<long long> value = toInteger(text);
  if (!value || *value < low || *value > high)
    refuse(option, text,
           high == std::numeric_limits<long long>::max()
               ? "an integer >= " + std::to_string(low)
               : "an integer in [" + std::to_string(low) + ", " + std::to_string(high) + "]",
           note);
  return *value;
}

double parseNumber(const std::string& option, const std::string& text, double low, double high, const std::string& note)
{
  const std::optional<double> value = toNumber(text);
  if (!value || *value < low || *value > high)
    refuse(option, text,
           std::isinf(high) ? "a number >= " + bound(low) : "a number in [" + bound(low) + ", " + bound(high) + "]",
           note);
  return *value;
}

double parsePositive(const std::string& option, const std::string& text, const std::string& note)
{
  const std::optional<double> value = toNumber(text);
  if (!value || !(*value > 0.0))
    refuse(option, text, "a number > 0", note);
  return *value;
}

Arguments::Arguments(int argc, char** argv) : argc_(argc), argv_(argv) {}

bool Arguments::next()
{
  if (index_ + 1 >= argc_)
    return false;
  flag_ = argv_[++index_];
  known_.clear();  // the hint is among the options this argument was compared with
  return true;
}

bool Arguments::is(const std::string& name)
{
  known_.push_back(name);
  return flag_ == name;
}

std::string Arguments::value()
{
  if (index_ + 1 >= argc_)
    throw UsageError(flag_ + " needs a value (see --help)");
  return argv_[++index_];
}

void Arguments::unknown() const
{
  // The closest known option (edit distance) is offered when it looks like a typo of this one: the same first
  // letter and about the same length ("--tolerence": "--tolerance"), not for any argument ("--bogus").
  const auto letters = [](const std::string& option)
  { return option.substr(std::min(option.find_first_not_of('-'), option.size())); };
  const std::string given = letters(flag_);
  std::string closest = flag_.rfind('-', 0) == 0 && !given.empty() ? closestName(flag_, known_) : "";
  const std::string known = letters(closest);
  const size_t length_difference = std::max(given.size(), known.size()) - std::min(given.size(), known.size());
  if (known.empty() || known[0] != given[0] || length_difference > 2)
    closest.clear();
  throw UsageError("unknown argument '" + flag_ + "' (" + (closest.empty() ? "" : "did you mean '" + closest + "'? ") +
                   "see --help)");
}

int runTool(const Tool& tool, int argc, char** argv, const std::function<int(int, char**)>& body)
{
  const auto oneLine = [](std::string reason)
  {
    for (char& c : reason)
      c = c == '\n' ? ' ' : c;
    return reason;
  };
  try
  {
    return body(argc, argv);
  }
  catch (const UsageError& e)
  {
    std::cerr << tool.name << ": " << oneLine(e.what()) << "\n" << tool.usage_after_error;
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << tool.name << ": " << (tool.error_word ? "error: " : "") << oneLine(e.what()) << "\n";
    return 1;
  }
}

}  // namespace cli
}  // namespace openable
