// The geometric verifier's tunables as configuration keys (verify_*): defaults, YAML, ranges, the one way
// from a Config to VerifierParams, and that they change neither the descriptors nor a running detector.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/verification/geometric_verifier.h"
#include "openable/detection/online_detector.h"
#include "openable/map/place_database.h"
#include "openable/map/reference_map.h"
#include "openable/map/session_map.h"

using namespace openable;

namespace
{
std::vector<Config::Key> verifierKeys()
{
  std::vector<Config::Key> keys;
  for (const auto& key : Config::keys())
    if (key.name.rfind("verify_", 0) == 0)
      keys.push_back(key);
  return keys;
}

/// Every VerifierParams field as text, by the name of its key.
std::map<std::string, std::string> fields(const VerifierParams& p)
{
  const auto text = [](double v)
  {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.17g", v);
    return std::string(buffer);
  };
  return {{"verify_max_features", text(p.max_features)},
          {"verify_ratio", text(p.ratio)},
          {"verify_max_hamming", text(p.max_hamming)},
          {"verify_min_inliers", text(p.min_inliers)},
          {"verify_ransac_threshold_px", text(p.ransac_threshold_px)},
          {"verify_ransac_confidence", text(p.ransac_confidence)},
          {"verify_ransac_iterations", text(p.ransac_iterations)},
          {"verify_min_parallax_deg", text(p.min_parallax_deg)},
          {"verify_identical_max_flow_px", text(p.identical_max_flow_px)},
          {"verify_stereo_max_row_diff_px", text(p.stereo_max_row_diff_px)},
          {"verify_stereo_min_disparity_px", text(p.stereo_min_disparity_px)},
          {"verify_stereo_max_disparity_px", text(p.stereo_max_disparity_px)},
          {"verify_stereo_max_hamming", text(p.stereo_max_hamming)},
          {"verify_min_stereo_points", text(p.min_stereo_points)}};
}

/// A valid configuration whose every verify_* key differs from its default.
Config nonDefaultVerifier()
{
  Config c = Config::paper();
  c.set("verify_max_features", "1500");
  c.set("verify_ratio", "0.7");
  c.set("verify_max_hamming", "70");
  c.set("verify_min_inliers", "20");
  c.set("verify_ransac_threshold_px", "1.5");
  c.set("verify_ransac_confidence", "0.99");
  c.set("verify_ransac_iterations", "500");
  c.set("verify_min_parallax_deg", "3");
  c.set("verify_identical_max_flow_px", "0.25");
  c.set("verify_stereo_max_row_diff_px", "1");
  c.set("verify_stereo_min_disparity_px", "2");
  c.set("verify_stereo_max_disparity_px", "120");
  c.set("verify_stereo_max_hamming", "40");
  c.set("verify_min_stereo_points", "25");
  return c;
}

bool anyErrorStartsWith(const std::vector<std::string>& errors, const std::string& start, const std::string& also)
{
  for (const auto& e : errors)
    if (e.rfind(start, 0) == 0 && e.find(also) != std::string::npos)
      return true;
  return false;
}
}  // namespace

TEST(VerifierKeys, OneKeyPerFieldNeitherLiveNorDescribing)
{
  const auto keys = verifierKeys();
  EXPECT_EQ(keys.size(), fields(VerifierParams()).size());
  for (const auto& key : keys)
  {
    EXPECT_TRUE(fields(VerifierParams()).count(key.name)) << key.name << " is no VerifierParams field";
    EXPECT_FALSE(key.live) << key.name;
    EXPECT_FALSE(key.describes) << key.name;
    EXPECT_TRUE(key.has_range) << key.name;
    EXPECT_EQ(std::find(Config::descriptorKeys().begin(), Config::descriptorKeys().end(), key.name),
              Config::descriptorKeys().end())
        << key.name;
  }
}

TEST(VerifierKeys, DefaultsAreVerifierParamsDefaults)
{
  EXPECT_EQ(fields(verifierParams(Config::paper())), fields(VerifierParams()));
  EXPECT_TRUE(Config::paper().validate().empty());
}

TEST(VerifierKeys, EveryKeyReachesItsField)
{
  const Config c = nonDefaultVerifier();
  ASSERT_TRUE(c.validate().empty()) << ::testing::PrintToString(c.validate());
  const auto got = fields(verifierParams(c));
  const auto defaults = fields(VerifierParams());
  for (const auto& key : verifierKeys())
  {
    EXPECT_NE(got.at(key.name), defaults.at(key.name)) << key.name << " did not reach VerifierParams";
    EXPECT_DOUBLE_EQ(std::stod(got.at(key.name)), std::stod(c.get(key.name))) << key.name;
  }
  EXPECT_TRUE(verifierParams(c).validate().empty());
}

TEST(VerifierKeys, YamlRoundTrip)
{
  const Config c = nonDefaultVerifier();
  const Config back = Config::fromYamlString(c.toYaml());
  for (const auto& key : verifierKeys())
    EXPECT_EQ(back.get(key.name), c.get(key.name)) << key.name;
  EXPECT_EQ(fields(verifierParams(back)), fields(verifierParams(c)));
  EXPECT_EQ(Config::fromYamlString("verify_min_inliers: 25\n").verify_min_inliers, 25);
}

TEST(VerifierKeys, YamlWithoutThemGivesTheDefaults)
{
  // A configuration written before the keys existed (and stored in older maps).
  const Config old = Config::fromYamlString("descriptor: HOG\nsequence_length: 30\n");
  EXPECT_EQ(fields(verifierParams(old)), fields(VerifierParams()));
}

TEST(VerifierKeys, OutOfRangeIsRefusedNamingTheKey)
{
  // Just outside each range as VerifierParams::validate() draws it (its low ends), or the table's high end.
  const std::map<std::string, std::string> bad = {
      {"verify_max_features", "49"},           {"verify_ratio", "0"},
      {"verify_max_hamming", "257"},           {"verify_min_inliers", "7"},
      {"verify_ransac_threshold_px", "0"},     {"verify_ransac_confidence", "1"},
      {"verify_ransac_iterations", "9"},       {"verify_min_parallax_deg", "-0.5"},
      {"verify_identical_max_flow_px", "-1"},  {"verify_stereo_max_row_diff_px", "0"},
      {"verify_stereo_min_disparity_px", "0"}, {"verify_stereo_max_disparity_px", "10001"},
      {"verify_stereo_max_hamming", "0"},      {"verify_min_stereo_points", "3"},
  };
  ASSERT_EQ(bad.size(), verifierKeys().size());
  for (const auto& [key, value] : bad)
  {
    Config c = Config::paper();
    c.set(key, value);
    EXPECT_TRUE(anyErrorStartsWith(c.validate(), key + ": value '", "not allowed"))
        << key << " = " << value << ": " << ::testing::PrintToString(c.validate());
    EXPECT_THROW(c.validateOrThrow(), Error) << key;
  }
  Config ratio = Config::paper();
  ratio.verify_ratio = 0.0;
  EXPECT_TRUE(anyErrorStartsWith(ratio.validate(), "verify_ratio: value '0'", "a number in (0, 1]"))
      << ::testing::PrintToString(ratio.validate());
  Config confidence = Config::paper();
  confidence.verify_ransac_confidence = 1.0;
  EXPECT_TRUE(anyErrorStartsWith(confidence.validate(), "verify_ransac_confidence", "a number in (0, 1)"))
      << ::testing::PrintToString(confidence.validate());
  Config nan = Config::paper();
  nan.verify_ransac_threshold_px = std::nan("");
  EXPECT_TRUE(anyErrorStartsWith(nan.validate(), "verify_ransac_threshold_px", "not allowed"));
}

TEST(VerifierKeys, DisparityBoundsRuleNamesBothKeys)
{
  Config c = Config::paper();
  c.verify_stereo_min_disparity_px = 200.0;  // in its range, but above the largest disparity (160)
  EXPECT_TRUE(anyErrorStartsWith(c.validate(), "verify_stereo_min_disparity_px/verify_stereo_max_disparity_px",
                                 "below the largest"))
      << ::testing::PrintToString(c.validate());
}

TEST(VerifierKeys, TheTablesRangesAreNoLooserThanTheVerifiers)
{
  // Each key at the edge of its range (just inside an open end) must give parameters the verifier takes.
  for (const auto& key : verifierKeys())
    for (const bool low : {true, false})
    {
      Config c = Config::paper();
      double value = low ? key.min : key.max;
      if (low && key.min_exclusive)
        value = key.min + 1e-6;
      if (!low && key.max_exclusive)
        value = key.max - 1e-6;
      c.set(key.name, key.type == "int" ? std::to_string(int(value)) : std::to_string(value));
      if (!c.validate().empty())
        continue;  // a rule across keys (the disparity bounds) refuses it already
      EXPECT_TRUE(verifierParams(c).validate().empty())
          << key.name << " = " << c.get(key.name) << ": " << ::testing::PrintToString(verifierParams(c).validate());
    }
}

TEST(VerifierKeys, OnlineDetectorBuildsItsVerifierFromTheConfig)
{
  const Config config = nonDefaultVerifier();
  OnlineDetector detector(config);
  PinholeCamera camera;
  camera.fx = camera.fy = 400.0;
  camera.cx = 320.0;
  camera.cy = 240.0;
  ASSERT_TRUE(detector.setCamera(camera));
  ASSERT_TRUE(detector.hasVerifier());
  EXPECT_EQ(fields(detector.verifier()->params()), fields(verifierParams(config)));

  // Not live: a running detector refuses another value and keeps the one in force.
  Config changed = config;
  changed.verify_min_inliers = 30;
  EXPECT_THROW(detector.updateConfig(changed), Error);
  EXPECT_EQ(detector.config().verify_min_inliers, 20);
  EXPECT_EQ(detector.verifier()->params().min_inliers, 20);
  // A live key alone still changes.
  Config live = config;
  live.threshold = 0.2;
  EXPECT_NO_THROW(detector.updateConfig(live));
}

TEST(VerifierKeys, DescriptorHashIgnoresThem)
{
  // They do not change what is stored: descriptors sent with another verifier are still comparable.
  EXPECT_EQ(descriptorHash(nonDefaultVerifier()), descriptorHash(Config::paper()));
  EXPECT_TRUE(descriptorDifferences(nonDefaultVerifier(), Config::paper()).empty());
}

TEST(VerifierKeys, MapsAreCompatibleWhateverTheVerifierKeys)
{
  // A map stamped with a configuration that predates the verify_* keys loads under any verifier values.
  const Config running = nonDefaultVerifier();
  const FrameDescriber describer(running);
  PlaceDatabase map(describer.layout(), 0, "camera_type: mono\ndescriptor: LDB\npatch_size: 64\n");
  map.add(describer.describeImage(cv::Mat(120, 160, CV_8UC1, cv::Scalar(90))));
  const std::string path = testing::TempDir() + "/openable_test_verifier_keys.map";
  map.save(path);
  EXPECT_NO_THROW(loadReferenceMap(path, running));
  std::remove(path.c_str());
}
