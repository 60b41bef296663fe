#pragma once
// The command line of the tools: strict numbers, the argument loop and runTool(), the main() around a tool.
//
//   int main(int argc, char** argv)
//   {
//     return openable::cli::runTool({"openable_x"}, argc, argv, [](int argc, char** argv) {
//       openable::cli::Arguments args(argc, argv);
//       while (args.next())
//         if (args.is("--frames"))
//           frames = args.integer(0, 1000000, "frames");
//         else
//           args.unknown();
//       ...
//     });
//   }

#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace openable
{
namespace cli
{
/// Bad usage: runTool prints "tool: reason" and returns 2 (bad input, any other exception, returns 1).
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// `text` as a whole as a decimal integer ("-" allowed first; no space, '+', fraction or exponent);
/// nothing when it is not one or does not fit in a long long.
std::optional<long long> toInteger(const std::string& text);
/// `text` as a whole as a finite decimal number ("12", "-0.5", "1e3"; no space, '+', hex, nan or inf).
std::optional<double> toNumber(const std::string& text);

/// The integer `text` given to `option`, in [low, high]; else UsageError
/// "OPTION: 'TEXT' is not allowed; expected an integer in [LOW, HIGH] (NOTE)" (">= LOW" when HIGH is the
/// largest long long; no parentheses without a note).
long long parseInteger(const std::string& option, const std::string& text, long long low, long long high,
                       const std::string& note = "");
/// The number `text` given to `option`, in [low, high] (high may be infinity); else UsageError
/// "OPTION: 'TEXT' is not allowed; expected a number in [LOW, HIGH] (NOTE)".
double parseNumber(const std::string& option, const std::string& text, double low, double high,
                   const std::string& note = "");
/// A number > 0 (and finite); else UsageError "...; expected a number > 0 (NOTE)".
double parsePositive(const std::string& option, const std::string& text, const std::string& note = "");

/// The argument loop: each argument in turn, the value of an option that takes one, and the errors for a
/// missing value or an unknown argument (with the closest known option as a hint).
class Arguments
{
public:
  /// argv[0] is the program and is skipped.
  Arguments(int argc, char** argv);

  /// Moves to the next argument; false when there is none left.
  bool next();
  /// The current argument.
  const std::string& flag() const
  {
    return flag_;
  }
  /// Whether the current argument is `name`. Every name asked about is remembered for unknown()'s hint.
  bool is(const std::string& name);
  /// --help or -h.
  bool isHelp()
  {
    return is("--help") || is("-h");
  }

  /// The current option's value (the next argument, consumed); UsageError "OPTION needs a value (see --help)".
  std::string value();
  /// The value as an integer in [low, high] (see parseInteger), of the type of the bounds.
  template <typename Int>
  Int integer(Int low, Int high, const std::string& note = "")
  {
    // An unsigned bound past the long long range (SIZE_MAX) is the long long range.
    constexpr long long kLargest = std::numeric_limits<long long>::max();
    const bool past = std::is_unsigned<Int>::value && static_cast<unsigned long long>(high) > kLargest;
    const long long top = past ? kLargest : static_cast<long long>(high);
    return static_cast<Int>(parseInteger(flag_, value(), static_cast<long long>(low), top, note));
  }
  /// The value as a number in [low, high] (see parseNumber).
  double number(double low, double high, const std::string& note = "")
  {
    return parseNumber(flag_, value(), low, high, note);
  }
  /// The value as a number > 0 (see parsePositive).
  double positive(const std::string& note = "")
  {
    return parsePositive(flag_, value(), note);
  }

  /// Throws UsageError "unknown argument 'ARG' (see --help)"; for a typo of an option asked about with is()
  /// (the closest by edit distance, with the same first letter and about as long), it names that option:
  /// "unknown argument '--tolerence' (did you mean '--tolerance'? see --help)".
  [[noreturn]] void unknown() const;

private:
  int argc_;
  char** argv_;
  int index_ = 0;
  std::string flag_;
  std::vector<std::string> known_;
};

/// How runTool reports a failure.
struct Tool
{
  std::string name;                 ///< every message starts "NAME: "
  bool error_word = true;           ///< bad input reads "NAME: error: reason" (false: "NAME: reason")
  std::string usage_after_error{};  ///< printed on stderr after a usage error's line (e.g. the usage)
};

/// A tool's main(): returns `body(argc, argv)`; a UsageError becomes one line "NAME: reason" on stderr and
/// exit status 2, any other exception (openable::Error: bad input) "NAME: error: reason" and 1. A reason's
/// line breaks become spaces, so every failure is one line.
int runTool(const Tool& tool, int argc, char** argv, const std::function<int(int, char**)>& body);

}  // namespace cli
}  // namespace openable
