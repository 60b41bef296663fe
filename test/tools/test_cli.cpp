// The tools' command line (cli.h): strict numbers, the argument loop and runTool's messages and exit codes.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
#include "openable/error.h"

namespace cli = openable::cli;

namespace
{
/// The message of the UsageError `f` throws; "" when it throws none.
template <typename F>
std::string usageError(F f)
{
  try
  {
    f();
  }
  catch (const cli::UsageError& e)
  {
    return e.what();
  }
  return "";
}

/// argv for Arguments: "tool" then `args`; the strings live as long as the object.
struct Argv
{
  explicit Argv(std::vector<std::string> args) : strings(std::move(args))
  {
    pointers.push_back(const_cast<char*>("tool"));
    for (std::string& s : strings)
      pointers.push_back(&s[0]);
    pointers.push_back(nullptr);
  }
  int argc() const
  {
    return static_cast<int>(pointers.size()) - 1;
  }
  char** argv()
  {
    return pointers.data();
  }
  std::vector<std::string> strings;
  std::vector<char*> pointers;
};

/// What runTool prints on stderr and returns for `body`.
struct Outcome
{
  int status;
  std::string err;
};
Outcome run(const cli::Tool& tool, const std::function<int(int, char**)>& body)
{
  Argv a({"x"});
  std::ostringstream captured;
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  const int status = cli::runTool(tool, a.argc(), a.argv(), body);
  std::cerr.rdbuf(old);
  return {status, captured.str()};
}
}  // namespace

TEST(CliNumbers, IntegersKnownAnswers)
{
  EXPECT_EQ(cli::toInteger("0"), 0);
  EXPECT_EQ(cli::toInteger("12"), 12);
  EXPECT_EQ(cli::toInteger("-7"), -7);
  EXPECT_EQ(cli::toInteger("007"), 7);
  EXPECT_EQ(cli::toInteger("9223372036854775807"), LLONG_MAX);
  EXPECT_EQ(cli::toInteger("-9223372036854775808"), LLONG_MIN);
  EXPECT_EQ(cli::parseInteger("--n", "1000000000", 0, 1000000000), 1000000000);
  EXPECT_EQ(cli::parseInteger("--n", "0", 0, 5), 0);
}

TEST(CliNumbers, IntegersRefuseAnythingButTheWholeNumber)
{
  for (const char* bad : {"", " ", "12x", "x12", " 12", "12 ", "+12", "1.0", "1e3", "0x10", "-", "nan", "inf",
                          "9223372036854775808", "-9223372036854775809", "99999999999999999999999"})
    EXPECT_FALSE(cli::toInteger(bad).has_value()) << "'" << bad << "'";
}

TEST(CliNumbers, IntegerErrorsNameTheOptionTheTextAndTheRange)
{
  EXPECT_EQ(usageError([] { cli::parseInteger("--tolerance", "-1", 0, 1000000000, "frames"); }),
            "--tolerance: '-1' is not allowed; expected an integer in [0, 1000000000] (frames)");
  EXPECT_EQ(usageError([] { cli::parseInteger("--tolerance", "", 0, 10); }),
            "--tolerance: '' is not allowed; expected an integer in [0, 10]");
  EXPECT_EQ(usageError([] { cli::parseInteger("--first", "12x", 0, LLONG_MAX, "a frame index"); }),
            "--first: '12x' is not allowed; expected an integer >= 0 (a frame index)");
  EXPECT_EQ(usageError([] { cli::parseInteger("--n", "11", 0, 10); }),
            "--n: '11' is not allowed; expected an integer in [0, 10]");
  // Too large for a long long is refused like any other out-of-range value, not wrapped or clamped.
  EXPECT_EQ(usageError([] { cli::parseInteger("--n", "99999999999999999999", 0, LLONG_MAX); }),
            "--n: '99999999999999999999' is not allowed; expected an integer >= 0");
}

TEST(CliNumbers, NumbersKnownAnswers)
{
  EXPECT_EQ(cli::toNumber("0"), 0.0);
  EXPECT_EQ(cli::toNumber("2.5"), 2.5);
  EXPECT_EQ(cli::toNumber("-0.25"), -0.25);
  EXPECT_EQ(cli::toNumber("1e3"), 1000.0);
  EXPECT_EQ(cli::toNumber(".5"), 0.5);
  EXPECT_EQ(cli::toNumber("5."), 5.0);
  EXPECT_FALSE(std::signbit(*cli::toNumber("-0")));  // -0 reads as 0 (printed "0", never "-0")
  EXPECT_DOUBLE_EQ(cli::parseNumber("--angle", "3.14159", 0.0, M_PI), 3.14159);
  EXPECT_EQ(cli::parseNumber("--d", "1000000", 0.0, 1e6), 1e6);
  EXPECT_EQ(cli::parsePositive("--distance", "6"), 6.0);
  EXPECT_EQ(cli::parsePositive("--distance", "1e-3"), 1e-3);
}

TEST(CliNumbers, NumbersRefuseNanInfinityAndPartialText)
{
  for (const char* bad :
       {"", "nan", "NaN", "inf", "-inf", "infinity", "12x", " 1", "1 ", "+1", "0x10", "1e", "e3", "--1", "1e400"})
    EXPECT_FALSE(cli::toNumber(bad).has_value()) << "'" << bad << "'";
}

TEST(CliNumbers, NumberErrorsNameTheOptionTheTextAndTheRange)
{
  EXPECT_EQ(usageError([] { cli::parseNumber("--keyframe-distance", "-1", 0.0, 1e6, "metres"); }),
            "--keyframe-distance: '-1' is not allowed; expected a number in [0, 1000000] (metres)");
  EXPECT_EQ(usageError([] { cli::parseNumber("--keyframe-angle", "4", 0.0, M_PI); }),
            "--keyframe-angle: '4' is not allowed; expected a number in [0, 3.14159]");
  EXPECT_EQ(usageError([] { cli::parseNumber("--time-offset", "nan", 0.0, 4e9, "seconds"); }),
            "--time-offset: 'nan' is not allowed; expected a number in [0, 4000000000] (seconds)");
  EXPECT_EQ(usageError([] { cli::parseNumber("--x", "-0.5", 0.5, INFINITY); }),
            "--x: '-0.5' is not allowed; expected a number >= 0.5");
  EXPECT_EQ(usageError([] { cli::parsePositive("--distance", "0", "metres"); }),
            "--distance: '0' is not allowed; expected a number > 0 (metres)");
  EXPECT_EQ(usageError([] { cli::parsePositive("--distance", "inf"); }),
            "--distance: 'inf' is not allowed; expected a number > 0");
}

TEST(CliArguments, WalksFlagsAndValues)
{
  Argv a({"--quiet", "--frames", "12", "--name", "--not-a-flag", "--distance", "2.5", "--first", "3"});
  cli::Arguments args(a.argc(), a.argv());
  bool quiet = false;
  int frames = 0;
  std::string name;
  double distance = 0.0;
  long first = -1;
  while (args.next())
  {
    if (args.is("--quiet"))
      quiet = true;
    else if (args.is("--frames"))
      frames = args.integer(0, INT_MAX);
    else if (args.is("--name"))
      name = args.value();  // a value may look like an option
    else if (args.is("--distance"))
      distance = args.positive();
    else if (args.is("--first"))
      first = args.integer(0L, LONG_MAX);
    else
      args.unknown();
  }
  EXPECT_TRUE(quiet);
  EXPECT_EQ(frames, 12);
  EXPECT_EQ(name, "--not-a-flag");
  EXPECT_EQ(distance, 2.5);
  EXPECT_EQ(first, 3);
}

TEST(CliArguments, UnsignedBoundsAndHelp)
{
  Argv a({"--every", "18446744073709551615", "--every", "5", "-h"});
  cli::Arguments args(a.argc(), a.argv());
  ASSERT_TRUE(args.next());
  ASSERT_TRUE(args.is("--every"));
  // SIZE_MAX as a bound means the long long range: the text is too large, and the message says the range.
  EXPECT_EQ(usageError([&] { args.integer<size_t>(0, SIZE_MAX); }),
            "--every: '18446744073709551615' is not allowed; expected an integer >= 0");
  ASSERT_TRUE(args.next());
  ASSERT_TRUE(args.is("--every"));
  EXPECT_EQ(args.integer<size_t>(0, SIZE_MAX), 5u);
  ASSERT_TRUE(args.next());
  EXPECT_TRUE(args.isHelp());
  EXPECT_FALSE(args.next());
}

TEST(CliArguments, MissingValueAndUnknownArguments)
{
  Argv a({"--output"});
  cli::Arguments args(a.argc(), a.argv());
  ASSERT_TRUE(args.next());
  EXPECT_EQ(usageError([&] { args.value(); }), "--output needs a value (see --help)");

  // The hint is the closest option the loop asked about before giving up.
  const auto unknown = [](const std::string& flag)
  {
    Argv b({flag});
    cli::Arguments loop(b.argc(), b.argv());
    return usageError(
        [&]
        {
          while (loop.next())
            if (!loop.is("--tolerance") && !loop.is("--output") && !loop.isHelp())
              loop.unknown();
        });
  };
  EXPECT_EQ(unknown("--tolerence"), "unknown argument '--tolerence' (did you mean '--tolerance'? see --help)");
  EXPECT_EQ(unknown("--outptu"), "unknown argument '--outptu' (did you mean '--output'? see --help)");
  EXPECT_EQ(unknown("--tolerance-frames"), "unknown argument '--tolerance-frames' (see --help)");  // too long
  // No option like it: no hint.
  EXPECT_EQ(unknown("--bogus"), "unknown argument '--bogus' (see --help)");
  EXPECT_EQ(unknown("-x"), "unknown argument '-x' (see --help)");
  // Not an option: no hint.
  EXPECT_EQ(unknown("stray"), "unknown argument 'stray' (see --help)");
  EXPECT_EQ(unknown("-"), "unknown argument '-' (see --help)");
  EXPECT_EQ(unknown("---"), "unknown argument '---' (see --help)");
  EXPECT_EQ(unknown("--help"), "");

  // Without any option asked about there is nothing to hint.
  Argv c({"--x"});
  cli::Arguments none(c.argc(), c.argv());
  ASSERT_TRUE(none.next());
  EXPECT_EQ(usageError([&] { none.unknown(); }), "unknown argument '--x' (see --help)");
}

TEST(CliArguments, NoArguments)
{
  Argv a({});
  cli::Arguments args(a.argc(), a.argv());
  EXPECT_FALSE(args.next());
}

TEST(CliRunTool, ExitCodesAndOneLineMessages)
{
  Outcome o = run({"tool"}, [](int argc, char** argv) { return argc == 2 && std::string(argv[1]) == "x" ? 0 : 9; });
  EXPECT_EQ(o.status, 0);
  EXPECT_EQ(o.err, "");
  o = run({"tool"}, [](int, char**) { return 3; });
  EXPECT_EQ(o.status, 3);

  o = run({"tool"}, [](int, char**) -> int { throw cli::UsageError("--x needs a value (see --help)"); });
  EXPECT_EQ(o.status, 2);
  EXPECT_EQ(o.err, "tool: --x needs a value (see --help)\n");

  o = run({"tool"}, [](int, char**) -> int { throw openable::Error("cannot read 'a'\nsecond line"); });
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err, "tool: error: cannot read 'a' second line\n");

  o = run({"tool"}, [](int, char**) -> int { throw std::runtime_error("plain"); });
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err, "tool: error: plain\n");
}

TEST(CliRunTool, ToolStyles)
{
  // openable_offline and openable_map: bad input without the word "error".
  Outcome o = run({"openable_map", false}, [](int, char**) -> int { throw openable::Error("no such map"); });
  EXPECT_EQ(o.status, 1);
  EXPECT_EQ(o.err, "openable_map: no such map\n");

  // kitti_to_bag: the usage after a usage error, not after bad input.
  o = run({"kitti_to_bag", true, "usage: kitti_to_bag ...\n"},
          [](int, char**) -> int { throw cli::UsageError("unknown argument '--x' (see --help)"); });
  EXPECT_EQ(o.status, 2);
  EXPECT_EQ(o.err, "kitti_to_bag: unknown argument '--x' (see --help)\nusage: kitti_to_bag ...\n");
  o = run({"kitti_to_bag", true, "usage: kitti_to_bag ...\n"},
          [](int, char**) -> int { throw openable::Error("bad"); });
  EXPECT_EQ(o.err, "kitti_to_bag: error: bad\n");
}
