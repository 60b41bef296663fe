// Geometric verification on real pairs: what the ratio test and RANSAC find on true revisits (same place by
// day and by night, from the other side of the path, EuRoC revisits, KITTI) and on non-revisits, and the
// VerifierParams defaults chosen from it. Prints the table of doc/results.md ("Geometric verification on
// real pairs"). Data: Gardens Point Walking (QUT; Suenderhauf et al. 2015), EuRoC MAV V1_01 (ETH ASL),
// KITTI odometry 06 (Geiger et al. 2013, CC BY-NC-SA 3.0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "euroc_revisits.h"
#include "openable/camera_calibration.h"
#include "openable/geometric_verifier.h"
#include "test_util.h"

namespace
{
using openable::FrameFeatures;
using openable::GeometricVerifier;
using openable::PinholeCamera;
using openable::Verification;
using openable::VerifierParams;

// Gardens Point ships no calibration. Assumed: a pinhole with a 65 deg horizontal field of view (a typical
// phone / action camera without fisheye), square pixels, principal point at the centre, no distortion, for
// the 960x540 day images; the 640x360 night images are the same camera at a lower resolution (same 16:9
// aspect), which PinholeCamera::image_size handles by resizing them to 960x540.
constexpr double kGardensPointHfovDeg = 65.0;
constexpr int kGardensPointFrames = 200;

PinholeCamera gardensPointCamera()
{
  PinholeCamera camera;
  camera.image_size = cv::Size(960, 540);
  camera.fx = camera.fy = 0.5 * camera.image_size.width / std::tan(0.5 * kGardensPointHfovDeg * CV_PI / 180.0);
  camera.cx = 0.5 * camera.image_size.width;
  camera.cy = 0.5 * camera.image_size.height;
  return camera;
}

PinholeCamera monoOf(PinholeCamera camera)
{
  camera.baseline = 0.0;
  return camera;
}

// One class of pairs (all true revisits or all non-revisits) verified with one camera.
struct PairClass
{
  std::string name;
  bool revisit;
  PinholeCamera camera;
  std::vector<std::pair<const FrameFeatures*, const FrameFeatures*>> pairs;  // (match, query)
};

// Features of every frame used, extracted once (extraction depends on max_features and the camera only,
// which the measurement and the defaults share).
class RealPairs : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    data_ = std::make_unique<Data>();
    Data& d = *data_;
    const VerifierParams params;
    const GeometricVerifier gp(gardensPointCamera(), params);
    for (int i = 0; i < kGardensPointFrames; ++i)
      for (const char* traversal : {"day_left", "day_right", "night_right"})
        d.gardens[traversal].push_back(gp.extract(openable_test::gardensPoint(traversal, i), cv::Mat(), i));

    const auto euroc = openable_test::euroc::loadRevisits();
    d.euroc_camera = euroc.camera;
    const GeometricVerifier euroc_stereo(euroc.camera, params);
    const GeometricVerifier euroc_mono(monoOf(euroc.camera), params);
    for (int i = 0; i < 4; ++i)
    {
      d.euroc_stereo.push_back(euroc_stereo.extract(euroc.left[i], euroc.right[i], i));
      d.euroc_mono.push_back(euroc_mono.extract(euroc.left[i], cv::Mat(), i));
    }

    // KITTI 06 was recorded the same day as 07 (2011_09_30): 07's calib.txt is its calibration.
    d.kitti_camera = openable::readCameraCalibration(openable_test::sharedData("kitti/07_first160/calib.txt"));
    const GeometricVerifier kitti_stereo(d.kitti_camera, params);
    const GeometricVerifier kitti_mono(monoOf(d.kitti_camera), params);
    const auto kitti = [](const std::string& name)
    { return cv::imread(openable_test::sharedData("kitti/06_frames/kitti06-" + name + ".png"), cv::IMREAD_GRAYSCALE); };
    for (const char* frame : {"01", "12", "435", "436", "12-R"})
      d.kitti_mono[frame] = kitti_mono.extract(kitti(frame));
    d.kitti_stereo12 = kitti_stereo.extract(kitti("12"), kitti("12-R"), 12);
  }
  static void TearDownTestSuite()
  {
    data_.reset();
  }

  static std::vector<PairClass> classes()
  {
    const Data& d = *data_;
    const auto& gp = d.gardens;
    const PinholeCamera gp_camera = gardensPointCamera();
    std::vector<PairClass> out;
    const auto gardens = [&](const std::string& name, bool revisit, const char* match, const char* query, int offset)
    {
      PairClass c{name, revisit, gp_camera, {}};
      for (int i = 0; i < kGardensPointFrames; ++i)
        c.pairs.emplace_back(&gp.at(match)[i], &gp.at(query)[(i + offset) % kGardensPointFrames]);
      out.push_back(c);
    };
    gardens("GP day_right -> night_right, same frame", true, "day_right", "night_right", 0);
    gardens("GP day_left -> day_right, same frame", true, "day_left", "day_right", 0);
    PairClass euroc_mono{"EuRoC mono, 1->0 and 3->2", true, monoOf(d.euroc_camera), {}};
    PairClass euroc_stereo{"EuRoC stereo, 1->0 and 3->2", true, d.euroc_camera, {}};
    for (const auto& [m, q] : {std::make_pair(1, 0), std::make_pair(3, 2)})
    {
      euroc_mono.pairs.emplace_back(&d.euroc_mono[m], &d.euroc_mono[q]);
      euroc_stereo.pairs.emplace_back(&d.euroc_stereo[m], &d.euroc_stereo[q]);
    }
    out.push_back(euroc_mono);
    out.push_back(euroc_stereo);
    const auto& k = d.kitti_mono;
    out.push_back({"KITTI 06 mono, 435->436, 1->12, 12 L->R",
                   true,
                   monoOf(d.kitti_camera),
                   {{&k.at("435"), &k.at("436")}, {&k.at("01"), &k.at("12")}, {&k.at("12"), &k.at("12-R")}}});
    out.push_back({"KITTI 06 stereo, 12->1", true, d.kitti_camera, {{&d.kitti_stereo12, &k.at("01")}}});

    gardens("GP day_right -> night_right, i vs i+100", false, "day_right", "night_right", 100);
    gardens("GP day_left -> day_right, i vs i+100", false, "day_left", "day_right", 100);
    gardens("GP day_right -> night_right, i vs i+20", false, "day_right", "night_right", 20);
    gardens("GP day_left -> day_right, i vs i+20", false, "day_left", "day_right", 20);
    PairClass euroc_non_mono{"EuRoC mono, 0/1 vs 2/3", false, monoOf(d.euroc_camera), {}};
    PairClass euroc_non_stereo{"EuRoC stereo, 0/1 vs 2/3", false, d.euroc_camera, {}};
    for (const auto& [m, q] : {std::make_pair(2, 0), std::make_pair(3, 0), std::make_pair(2, 1), std::make_pair(3, 1)})
    {
      euroc_non_mono.pairs.emplace_back(&d.euroc_mono[m], &d.euroc_mono[q]);
      euroc_non_stereo.pairs.emplace_back(&d.euroc_stereo[m], &d.euroc_stereo[q]);
    }
    out.push_back(euroc_non_mono);
    out.push_back(euroc_non_stereo);
    out.push_back({"KITTI 06 mono, 1/12 vs 435/436 (134 m)",
                   false,
                   monoOf(d.kitti_camera),
                   {{&k.at("01"), &k.at("435")},
                    {&k.at("01"), &k.at("436")},
                    {&k.at("12"), &k.at("435")},
                    {&k.at("12"), &k.at("436")}}});
    out.push_back({"KITTI 06 stereo, 12 vs 435/436",
                   false,
                   d.kitti_camera,
                   {{&d.kitti_stereo12, &k.at("435")}, {&d.kitti_stereo12, &k.at("436")}}});
    return out;
  }

  struct Data
  {
    std::map<std::string, std::vector<FrameFeatures>> gardens;
    PinholeCamera euroc_camera, kitti_camera;
    std::vector<FrameFeatures> euroc_stereo, euroc_mono;
    std::map<std::string, FrameFeatures> kitti_mono;
    FrameFeatures kitti_stereo12;
  };
  static std::unique_ptr<Data> data_;
};
std::unique_ptr<RealPairs::Data> RealPairs::data_;

int percentile(std::vector<int> values, double p)
{
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(std::lround(p * (values.size() - 1)))];
}

// The distribution of every class with a permissive verifier (min_inliers 8, the smallest allowed: RANSAC
// runs on every pair with 8 matches), and how many pairs each candidate min_inliers would accept. A pair
// with fewer than 8 ratio-test matches counts 0 inliers.
TEST_F(RealPairs, MeasureMatchesAndInliers)
{
  VerifierParams permissive;
  permissive.min_inliers = 8;
  const int candidates[] = {30, 20, 15, 12};
  std::printf("| pairs | n | ratio-test matches p10 / p50 / p90 / max | inliers p10 / p50 / p90 / max |");
  for (int c : candidates)
    std::printf(" accepted, min_inliers %d |", c);
  std::printf("\n|---|---|---|---|");
  for (size_t i = 0; i < std::size(candidates); ++i)
    std::printf("---|");
  std::printf("\n");
  for (const auto& c : classes())
  {
    const GeometricVerifier verifier(c.camera, permissive);
    std::vector<int> matches, inliers;
    std::vector<int> accepted(std::size(candidates), 0);
    for (const auto& [match, query] : c.pairs)
    {
      const Verification v = verifier.verify(*match, *query);
      matches.push_back(v.matches);
      inliers.push_back(v.inliers);
      // Every threshold check is "count >= min_inliers" and RANSAC does not depend on it: a pair accepted
      // here with k inliers is accepted by any min_inliers <= k.
      for (size_t t = 0; t < std::size(candidates); ++t)
        accepted[t] += v.accepted() && v.inliers >= candidates[t];
    }
    std::printf("| %s%s | %zu | %d / %d / %d / %d | %d / %d / %d / %d |",
                c.revisit ? "" : "NON-revisit: ", c.name.c_str(), c.pairs.size(), percentile(matches, 0.1),
                percentile(matches, 0.5), percentile(matches, 0.9), percentile(matches, 1.0), percentile(inliers, 0.1),
                percentile(inliers, 0.5), percentile(inliers, 0.9), percentile(inliers, 1.0));
    for (int a : accepted)
      std::printf(" %d |", a);
    std::printf("\n");
  }
}

}  // namespace
