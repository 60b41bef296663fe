#pragma once
// openable_eval's command line: the options, their parsing and checks (the modes are in openable_eval.cpp).

#include <stdexcept>
#include <string>
#include <vector>

#include "openable/evaluation/evaluation.h"

namespace openable_eval
{
extern const char kUsage[];

/// Bad usage (exit status 2), as opposed to bad input (exit status 1).
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

struct Options
{
  std::vector<std::string> matrices;
  std::vector<std::string> names;
  std::string mask;
  std::string mask_dark;
  int tolerance = -1;
  int joined = -1;
  std::string truth_matrix;
  std::string published;
  std::string decisions;
  int frames = 0;
  std::string pairs;
  int pair_tolerance = 0;
  std::string poses;
  double distance = openable::kDefaultLoopDistance;
  int exclusion = openable::kDefaultLoopExclusion;
  std::string output;
  std::string title = "Precision-recall";
  std::string compare;
  bool sweep = false;
  bool quiet = false;
  bool help = false;
};

/// Reads the command line; throws UsageError naming the option.
Options parseArguments(int argc, char** argv);
/// Options that do not go together, or a missing ground truth; throws UsageError.
void checkOptions(const Options& o);

}  // namespace openable_eval
