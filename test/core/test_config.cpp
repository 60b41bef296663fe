#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <fstream>
#include <functional>

#include "openable/config.h"
#include "openable/error.h"

using namespace openable;

namespace
{
bool anyErrorMentions(const std::vector<std::string>& errors, const std::string& a, const std::string& b)
{
  for (const auto& e : errors)
    if (e.find(a) != std::string::npos && e.find(b) != std::string::npos)
      return true;
  return false;
}
}  // namespace

TEST(Config, PaperValuesAreThePapersAndValid)
{
  const Config c = Config::paper();
  EXPECT_EQ(c.camera_type, "mono");
  EXPECT_EQ(c.description_type, "global");
  EXPECT_EQ(c.patch_size, 64);
  EXPECT_EQ(c.grid_x, 1);
  EXPECT_EQ(c.grid_y, 1);
  EXPECT_EQ(c.panoramas, 6);
  EXPECT_FALSE(c.illumination_invariance);
  EXPECT_DOUBLE_EQ(c.alpha, 0.47);
  EXPECT_EQ(c.descriptor, "LDB");
  EXPECT_EQ(c.sequence_length, 1);
  EXPECT_EQ(c.max_pace, 1);
  EXPECT_DOUBLE_EQ(c.threshold, -1.0);
  EXPECT_DOUBLE_EQ(c.min_uniqueness, 0.0);
  EXPECT_EQ(c.color_map, 7);
  EXPECT_TRUE(c.validate().empty());
}

TEST(Config, DefaultsPublishAtAnyPaceAndAreValid)
{
  const Config c;
  EXPECT_EQ(c.descriptor, "HOG-B");
  EXPECT_EQ(c.sequence_length, 30);
  EXPECT_EQ(c.max_pace, 3);
  EXPECT_GT(c.min_uniqueness, 0.0) << "a gate must be set, or nothing is published";
  EXPECT_GT(c.standstill_distance, 0.0);
  EXPECT_TRUE(c.validate().empty());
}

namespace
{
/// Every key of a shipped YAML file equals the given configuration, and every key is written in the file.
void expectFileHoldsEveryKey(const std::string& name, const Config& expected)
{
  const std::string path = std::string(OPENABLE_SOURCE_DIR) + "/config/" + name;
  const Config file = Config::fromYamlFile(path);
  for (const auto& key : Config::keys())
    EXPECT_EQ(file.get(key.name), expected.get(key.name)) << name << ": " << key.name;
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& key : Config::keys())
    EXPECT_NE(text.find("\n" + key.name + ":"), std::string::npos) << key.name << " is not documented in " << name;
}
}  // namespace

TEST(Config, PaperYamlFileHoldsEveryKeyWithThePapersValue)
{
  expectFileHoldsEveryKey("paper.yaml", Config::paper());
}

// A bare nodelet, openable_offline without --config and a partial YAML all start from the code's defaults:
// they must be default.yaml's, or "one set of defaults" drifts.
TEST(Config, DefaultYamlFileHoldsEveryKeyWithTheCodesDefault)
{
  expectFileHoldsEveryKey("default.yaml", Config());
}

TEST(Config, SetGetAndYamlRoundTrip)
{
  Config c;
  c.set("sequence_length", "25");
  c.set("illumination_invariance", "true");
  c.set("threshold", "0.125");
  c.set("descriptor", "ORB");
  EXPECT_EQ(c.sequence_length, 25);
  EXPECT_TRUE(c.illumination_invariance);
  EXPECT_DOUBLE_EQ(c.threshold, 0.125);
  const Config back = Config::fromYamlString(c.toYaml());
  for (const auto& key : Config::keys())
    EXPECT_EQ(back.get(key.name), c.get(key.name)) << key.name;
}

TEST(Config, UnknownKeyAndWrongTypeAreClearErrors)
{
  Config c;
  try
  {
    c.set("sequence_lenght", "3");
    FAIL();
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("sequence_lenght"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("sequence_length"), std::string::npos);  // lists the known keys
  }
  EXPECT_THROW(c.set("patch_size", "big"), Error);
  EXPECT_THROW(c.set("patch_size", "64.5"), Error);
  EXPECT_THROW(c.set("illumination_invariance", "maybe"), Error);
  EXPECT_THROW(Config::fromYamlString("patch_size: [1, 2]"), Error);
  EXPECT_THROW(Config::fromYamlString("- a\n- b"), Error);
  EXPECT_THROW(Config::fromYamlString("patch_size: [1, 2"), Error);
  EXPECT_THROW(Config::fromYamlFile("/nonexistent/config.yaml"), Error);
}

TEST(Config, ValidateNamesKeyValueAndAllowedValues)
{
  Config c;
  c.camera_type = "fisheye";
  c.sequence_length = 0;
  c.threshold = 1.5;
  c.descriptor = "AKAZE";
  c.patch_size = 4;
  c.color_map = 12;
  const auto errors = c.validate();
  EXPECT_TRUE(anyErrorMentions(errors, "camera_type", "mono | stereo | panoramic"));
  EXPECT_TRUE(anyErrorMentions(errors, "sequence_length", "'0'"));
  EXPECT_TRUE(anyErrorMentions(errors, "threshold", "-1 (off) or a number in [0, 1]"));
  EXPECT_TRUE(anyErrorMentions(errors, "descriptor", "LDB"));
  EXPECT_TRUE(anyErrorMentions(errors, "patch_size", "[8, 1024]"));
  EXPECT_TRUE(anyErrorMentions(errors, "color_map", "[0, 11]"));
  EXPECT_THROW(c.validateOrThrow(), Error);

  Config stereo_descriptor_in_mono;
  stereo_descriptor_in_mono.descriptor = "D-LDB";
  EXPECT_TRUE(anyErrorMentions(stereo_descriptor_in_mono.validate(), "descriptor", "camera_type stereo"));

  Config threshold_nan;
  threshold_nan.threshold = std::nan("");
  EXPECT_FALSE(threshold_nan.validate().empty());
  Config threshold_negative;
  threshold_negative.threshold = -0.5;
  EXPECT_FALSE(threshold_negative.validate().empty());
}

// Problems are values: the keys a rule involves (both keys of a rule across two), the value, what was
// expected; validate() is their text, so nothing downstream parses key names out of a message.
TEST(ConfigProblems, NameEveryKeyOfTheRuleAsValues)
{
  Config c;
  c.description_type = "global";
  c.grid_x = 3;
  c.verify_stereo_min_disparity_px = 50.0;
  c.verify_stereo_max_disparity_px = 10.0;
  c.sequence_length = 0;
  const auto problems = c.problems();
  const auto has = [&](std::vector<std::string> keys)
  { return std::any_of(problems.begin(), problems.end(), [&](const ConfigProblem& p) { return p.keys == keys; }); };
  EXPECT_TRUE(has({"grid_x", "grid_y"}));
  EXPECT_TRUE(has({"verify_stereo_min_disparity_px", "verify_stereo_max_disparity_px"}));
  EXPECT_TRUE(has({"sequence_length"}));
  ASSERT_EQ(c.validate().size(), problems.size());
  for (size_t i = 0; i < problems.size(); ++i)
    EXPECT_EQ(c.validate()[i], problems[i].message());
  EXPECT_EQ(ConfigProblem({{"a", "b"}, "1 / 2", "something"}).message(),
            "a/b: value '1 / 2' is not allowed; expected something");
  EXPECT_TRUE(Config().problems().empty());
}

// sanitized() resets exactly the keys broken rules name, rule after rule, leaves the rest and the fixed keys
// alone, and says what it did.
TEST(ConfigProblems, SanitizedResetsTheKeysOfEachBrokenRule)
{
  Config fallback;
  fallback.threshold = 0.05;
  Config requested = fallback;
  requested.threshold = 5.0;           // out of range: falls back
  requested.sequence_length = 4;       // valid: kept
  requested.min_sequence_length = 9;   // above sequence_length: falls back
  std::vector<ConfigRepair> repairs;
  const Config repaired = requested.sanitized(fallback, repairs);
  EXPECT_TRUE(repaired.problems().empty());
  EXPECT_EQ(repaired.threshold, 0.05);
  EXPECT_EQ(repaired.sequence_length, 4);
  EXPECT_EQ(repaired.min_sequence_length, fallback.min_sequence_length);
  ASSERT_EQ(repairs.size(), 2u);
  EXPECT_EQ(repairs[0].reset_keys, std::vector<std::string>{"threshold"});
  EXPECT_EQ(repairs[1].reset_keys, std::vector<std::string>{"min_sequence_length"});

  // A fixed key is never reset: the problem is reported, the result stays invalid.
  Config wrong_camera;
  wrong_camera.camera_type = "fisheye";
  repairs.clear();
  const Config kept = wrong_camera.sanitized(fallback, repairs, {"camera_type"});
  EXPECT_EQ(kept.camera_type, "fisheye");
  EXPECT_FALSE(kept.problems().empty());
  ASSERT_FALSE(repairs.empty());
  EXPECT_TRUE(repairs[0].reset_keys.empty());
}

// ValidConfig is the one validation of a start: it refuses an invalid configuration with every problem, and
// what is built from it (OnlineDetector, LoopDetector, FrameDescriber) does not validate again.
TEST(ConfigProblems, ValidConfigRefusesWhatValidateRefuses)
{
  Config bad;
  bad.sequence_length = 0;
  bad.descriptor = "AKAZE";
  try
  {
    ValidConfig valid(bad);
    FAIL() << "an invalid configuration was accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("sequence_length"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("descriptor"), std::string::npos) << e.what();
  }
  const ValidConfig valid{Config()};
  EXPECT_EQ(valid->descriptor, Config().descriptor);
}

TEST(Config, AlphaFromPeakWavelengthsReproducesKittiValue)
{
  // Paper: PointGrey Flea2 with peaks at 610, 535 and 470 nm gives alpha = 0.47.
  EXPECT_NEAR(alphaFromWavelengths(610, 535, 470), 0.4706, 1e-4);
  EXPECT_THROW(alphaFromWavelengths(0, 535, 470), Error);
}

// Issue 9 (hardening): inputs that used to run silently with defaults, escape as yaml-cpp exceptions or
// print wrapped numbers.
namespace
{
std::string errorOf(const std::function<void()>& action)
{
  try
  {
    action();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "(no openable::Error)";
}

std::string writeTemp(const std::string& name, const std::string& text)
{
  const std::string path = testing::TempDir() + "/openable_test_config_" + name;
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(ConfigHardening, FolderAsConfigFileIsAnErrorNotTheDefaults)
{
  const std::string folder = testing::TempDir();
  const std::string message = errorOf([&] { Config::fromYamlFile(folder); });
  EXPECT_NE(message.find(folder), std::string::npos) << message;
  EXPECT_NE(message.find("is a folder"), std::string::npos) << message;
}

TEST(ConfigHardening, ListOrMappingValueNamesFileAndKey)
{
  const std::string list = writeTemp("list.yaml", "patch_size: 64\nsequence_length: [1, 2]\n");
  std::string message = errorOf([&] { Config::fromYamlFile(list); });
  EXPECT_NE(message.find(list), std::string::npos) << message;
  EXPECT_NE(message.find("sequence_length"), std::string::npos) << message;
  EXPECT_NE(message.find("expected a single value"), std::string::npos) << message;

  const std::string mapping = writeTemp("map.yaml", "descriptor:\n  name: LDB\n");
  message = errorOf([&] { Config::fromYamlFile(mapping); });
  EXPECT_NE(message.find(mapping), std::string::npos) << message;
  EXPECT_NE(message.find("descriptor"), std::string::npos) << message;
}

TEST(ConfigHardening, ListAsKeyIsAnOpenableError)
{
  // What a corrupt map's stored configuration held (test/data/repro/config_seqkey.map): a complex key.
  const std::string message = errorOf([] { Config::fromYamlString("? [a, b]\n: 1\n"); });
  EXPECT_NE(message.find("[a, b]"), std::string::npos) << message;
  EXPECT_NE(message.find("expected a key name"), std::string::npos) << message;
}

TEST(ConfigHardening, HistoryBoundMessageDoesNotWrap)
{
  Config c = Config::paper();
  c.max_history = 1000;
  c.exclusion_window = 2147483647;
  EXPECT_TRUE(anyErrorMentions(c.validate(), "max_history", "= 4294967296")) << ::testing::PrintToString(c.validate());
  c.exclusion_window = 50;
  c.sequence_length = 2147483647;
  EXPECT_TRUE(anyErrorMentions(c.validate(), "max_history", "= 4294967394")) << ::testing::PrintToString(c.validate());
}

TEST(ConfigHardening, AbsurdMemoryPerFrameIsRefusedWithTheFigure)
{
  Config c;
  c.description_type = "grid";
  c.grid_x = 64;
  c.grid_y = 64;
  c.patch_size = 1024;
  // 4096 cells of 1024 x 1024 pixels at 16 bytes each: 64 GiB per frame.
  EXPECT_TRUE(anyErrorMentions(c.validate(), "68719476736 bytes per frame", "patch_size"))
      << ::testing::PrintToString(c.validate());
  // A 64x64 grid of 128 px patches is the largest that fits the 1 GiB bound.
  c.patch_size = 128;
  EXPECT_TRUE(c.validate().empty()) << ::testing::PrintToString(c.validate());
  c.patch_size = 129;
  EXPECT_FALSE(c.validate().empty());
}

namespace
{
/// The gen.add(...) entries of cfg/Detector.cfg: name -> {type, default, min, max} as written.
struct CfgEntry
{
  std::string type, description, default_value, min, max;
};
std::map<std::string, CfgEntry> readDetectorCfg()
{
  std::ifstream in(std::string(OPENABLE_SOURCE_DIR) + "/cfg/Detector.cfg");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::map<std::string, CfgEntry> entries;
  // gen.add("name", type_t, level, "description", default[, min, max][, edit_method=...])
  const std::regex add(R"re(gen\.add\("(\w+)",\s*(\w+),\s*\w+,\s*"([^"]*)",\s*([^,\)]+)(?:,\s*([^,\)=]+),\s*([^,\)=]+))?)re");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), add); it != std::sregex_iterator(); ++it)
    entries[(*it)[1]] = {(*it)[2], (*it)[3], (*it)[4], (*it)[5], (*it)[6]};
  return entries;
}

double number(const std::string& text)
{
  if (text == "True")
    return 1;
  if (text == "False")
    return 0;
  return std::stod(text);
}
}  // namespace

TEST(Config, DynamicReconfigureHoldsEveryLiveKeyWithItsDefaultAndRangeButDoesNotClamp)
{
  const auto cfg = readDetectorCfg();
  ASSERT_GE(cfg.size(), 10u);
  const Config defaults;
  for (const auto& key : Config::keys())
  {
    const auto it = cfg.find(key.name);
    if (!key.live)
    {
      EXPECT_TRUE(it == cfg.end()) << key.name << " cannot change live but is in cfg/Detector.cfg";
      continue;
    }
    ASSERT_TRUE(it != cfg.end()) << key.name << " is live but missing from cfg/Detector.cfg";
    const std::string type = key.type == "int" ? "int_t" : key.type == "double" ? "double_t" : "bool_t";
    EXPECT_EQ(it->second.type, type) << key.name;
    const std::string value = defaults.get(key.name);
    const double expected = value == "true" ? 1.0 : value == "false" ? 0.0 : std::stod(value);
    EXPECT_DOUBLE_EQ(number(it->second.default_value), expected) << key.name;
    if (key.has_range)
    {
      // No min/max for dynamic_reconfigure: its server would clamp an out-of-range request to them before
      // LiveReconfigure could refuse it (threshold 5 silently became 1). The range is stated in the
      // description instead, as "range [min, max]" (threshold: "range -1 or [0, 1]").
      EXPECT_TRUE(it->second.min.empty()) << key.name << " has a min/max in cfg/Detector.cfg, which clamps silently";
      const std::string& description = it->second.description;
      std::smatch range;
      ASSERT_TRUE(std::regex_search(description, range, std::regex(R"re(range (-1 or )?\[([^,\]]+), ([^\]]+)\])re")))
          << key.name << ": no 'range [min, max]' in its description: " << description;
      EXPECT_DOUBLE_EQ(range[1].matched ? -1.0 : number(range[2].str()), key.min) << key.name;
      EXPECT_DOUBLE_EQ(number(range[3].str()), key.max) << key.name;
    }
  }
}

TEST(Config, DescriptorAndLiveKeysComeFromTheTable)
{
  for (const auto& name : Config::descriptorKeys())
    EXPECT_FALSE(std::find(Config::liveKeys().begin(), Config::liveKeys().end(), name) != Config::liveKeys().end())
        << name << " changes the descriptors, so it cannot be live";
  EXPECT_EQ(Config::descriptorKeys().size(), 14u);
  EXPECT_NE(std::find(Config::liveKeys().begin(), Config::liveKeys().end(), "threshold"), Config::liveKeys().end());
  EXPECT_EQ(std::find(Config::liveKeys().begin(), Config::liveKeys().end(), "max_history"), Config::liveKeys().end());
}

TEST(Config, EveryShippedConfigurationListsEveryKey)
{
  for (const char* name : {"default", "paper", "gardens_point", "nordland"})
  {
    const std::string path = std::string(OPENABLE_SOURCE_DIR) + "/config/" + name + ".yaml";
    EXPECT_NO_THROW(Config::fromYamlFile(path).validateOrThrow()) << path;
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& key : Config::keys())
      EXPECT_NE(text.find("\n" + key.name + ":"), std::string::npos) << key.name << " is missing from " << path;
  }
}
