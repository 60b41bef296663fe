// Issue 22, "nothing bad gets in": the input contract (openable/input_contract.h) at every entry of the core:
// poses (findings 1), stamps (2) and degenerate frames (3) refused, each with its own reason, nothing stored.
// Real frames: Gardens Point Walking (QUT; Suenderhauf et al. 2015) and Nordland (NRK, CC BY).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "openable/description/frame_describer.h"
#include "openable/io/image_source.h"
#include "openable/description/input_contract.h"
#include "openable/detection/online_detector.h"
#include "openable/server/place_server.h"
#include "openable/io/pose_file.h"
#include "openable/map/session_map.h"
#include "test_util.h"

using namespace openable;

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

Config shipped(const std::string& name)
{
  return Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/" + name + ".yaml");
}

std::string tempPath(const std::string& name)
{
  const std::string dir = ::testing::TempDir() + "openable_input_contract";
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}

/// The reason of the FrameRefused that `process` throws, "" when it throws none.
std::string frameRefusal(OnlineDetector& detector, const FrameInput& input)
{
  try
  {
    detector.process(input);
  }
  catch (const FrameRefused& e)
  {
    EXPECT_GT(std::string(e.what()).find("expected"), 0u) << e.what();
    return e.reason();
  }
  return "";
}

FrameInput realFrame(int index, double stamp)
{
  FrameInput input;
  input.image = openable_test::gardensPoint("day_right", index);
  input.stamp = stamp;
  return input;
}

PlaceDescriptorInput place(const std::string& robot, uint64_t frame, double stamp, const Config& config)
{
  static std::map<uint64_t, FrameDescriptor> cache;
  FrameDescriptor& d = cache[frame];
  if (d.empty())
    d = FrameDescriber(config).describeImage(openable_test::gardensPoint("day_left", int(frame % 200)));
  PlaceDescriptorInput in;
  in.robot = robot;
  in.session = robot;
  in.frame_id = frame;
  in.stamp = stamp;
  in.config_hash = descriptorHash(config);
  in.descriptor = d;
  return in;
}

std::string serverRefusal(PlaceServer& server, const PlaceDescriptorInput& in)
{
  try
  {
    server.process(in);
  }
  catch (const DescriptorRefused& e)
  {
    return e.reason();
  }
  return "";
}
}  // namespace

// ---- finding 1: poses --------------------------------------------------------------------------------------

TEST(InputContract, PosesMustBeFiniteWithAUnitQuaternion)
{
  Pose near{{1, 2, 3, 0, 0, 0, 1.001}};
  EXPECT_TRUE(checkPose(near).ok());
  EXPECT_DOUBLE_EQ(near[6], 1.0);  // normalised
  Pose nan{{kNaN, 0, 0, 0, 0, 0, 1}}, inf{{0, 0, 0, 0, kInf, 0, 1}}, zero{{0, 0, 0, 0, 0, 0, 0}},
      two{{0, 0, 0, 0, 0, 0, 2}};
  EXPECT_EQ(checkPose(nan).reason, "pose not finite");
  EXPECT_EQ(checkPose(inf).reason, "pose not finite");
  EXPECT_EQ(checkPose(zero).reason, "zero quaternion");
  EXPECT_EQ(checkPose(two).reason, "quaternion not unit");
  EXPECT_NE(checkPose(two).what.find("norm 2"), std::string::npos) << checkPose(two).what;
}

TEST(InputContract, PlaceServerRefusesNaNInfAndZeroQuaternionPoses)
{
  const Config config = shipped("gardens_point");
  PlaceServer server(config);
  double stamp = 1000.0;
  for (const Pose& bad : {Pose{{kNaN, 0, 0, 0, 0, 0, 1}}, Pose{{0, kInf, 0, 0, 0, 0, 1}}, Pose{{0, 0, 0, 0, 0, 0, 0}},
                          Pose{{0, 0, 0, kNaN, 0, 0, 1}}})
  {
    PlaceDescriptorInput in = place("r1", 0, stamp += 1.0, config);
    in.has_pose = true;
    in.pose = bad;
    EXPECT_NE(serverRefusal(server, in), "");
  }
  EXPECT_EQ(server.map().frameCount(), 0u);
  EXPECT_EQ(server.refused().at("pose not finite"), 3u);
  EXPECT_EQ(server.refused().at("zero quaternion"), 1u);
  // A near-unit quaternion is stored normalised, and what the server reports carries no NaN.
  PlaceDescriptorInput in = place("r1", 0, stamp += 1.0, config);
  in.has_pose = true;
  in.pose = {{1, 2, 3, 0, 0, 0, 0.999}};
  const ServerCandidates answer = server.process(in);
  EXPECT_DOUBLE_EQ(answer.query_pose[6], 1.0);
  EXPECT_DOUBLE_EQ(server.map().frames(0).info(0).pose[6], 1.0);
}

TEST(InputContract, DetectorRefusesAFrameWithANaNPoseBeforeStoringIt)
{
  OnlineDetector detector(shipped("default"));
  FrameInput input = realFrame(10, 10.0);
  input.has_pose = true;
  input.pose = {{0, 0, kNaN, 0, 0, 0, 1}};
  EXPECT_EQ(frameRefusal(detector, input), "pose not finite");
  input.pose = {{0, 0, 0, 0, 0, 0, 0}};
  EXPECT_EQ(frameRefusal(detector, input), "zero quaternion");
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 0u);
  input.pose = {{0, 0, 0, 0, 0, 0, 1.002}};
  const FrameOutcome outcome = detector.process(input);
  EXPECT_TRUE(outcome.stored);
  EXPECT_DOUBLE_EQ(outcome.query.pose[6], 1.0);
}

TEST(InputContract, PoseFileRefusesANonUnitQuaternion)
{
  const std::string path = tempPath("norm2.txt");
  std::ofstream(path) << "0.1 0 0 0 0 0 0 1\n0.2 1 2 3 0 0 0 2\n";
  try
  {
    readPoseFile(path);
    ADD_FAILURE() << "a quaternion of norm 2 was accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find(path + ":2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unit quaternion"), std::string::npos) << e.what();
  }
}

TEST(InputContract, AMapHoldingANaNPoseIsRefusedOnLoad)
{
  // A map saved before issue 22 by a place server that stored NaN poses.
  const Config config = shipped("gardens_point");
  const FrameDescriber describer(config);
  SessionMap map(describer.layout(), config.toYaml());
  const uint32_t session = map.addSession(SessionInfo{"r1", "r1", 1.0}, 0);
  FrameInfo info;
  info.stamp = 1.0;
  info.has_pose = true;
  info.pose = {{kNaN, 0, 0, 0, 0, 0, 1}};
  map.add(session, describer.describeImage(openable_test::gardensPoint("day_left", 0)), info);
  const std::string path = tempPath("nan_pose.map");
  map.save(path);
  try
  {
    SessionMap::load(path);
    ADD_FAILURE() << "a map with a NaN pose loaded";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("pose x is nan"), std::string::npos) << e.what();
  }
}

// ---- finding 2: stamps -------------------------------------------------------------------------------------

TEST(InputContract, DetectorRefusesStampZeroAfterStampedFramesWithoutAReset)
{
  OnlineDetector detector(shipped("default"));
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(detector.process(realFrame(10 + i, 1000.0 + i)).stored);
  EXPECT_EQ(frameRefusal(detector, realFrame(13, 0.0)), "stamp 0");
  EXPECT_EQ(frameRefusal(detector, realFrame(13, kNaN)), "stamp not finite");
  EXPECT_EQ(frameRefusal(detector, realFrame(13, -1.0)), "negative stamp");
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 3u);
  // A stamp before the previous one stays a time jump (a caller may reset on it, e.g. a bag that loops).
  EXPECT_EQ(detector.process(realFrame(13, 1.0)).status, FrameStatus::TimeJump);
  EXPECT_TRUE(detector.process(realFrame(13, 1003.0)).stored);
}

TEST(InputContract, UnstampedStreamsStayUnstampedUnlessStampsAreRequired)
{
  OnlineDetector folder(shipped("default"));  // a folder of images: no stamps at all
  EXPECT_TRUE(folder.process(realFrame(10, 0.0)).stored);
  EXPECT_TRUE(folder.process(realFrame(11, 0.0)).stored);
  OnlineOptions ros;
  ros.require_stamps = true;  // the nodelets: header.stamp 0 is unset
  OnlineDetector nodelet(shipped("default"), ros);
  EXPECT_EQ(frameRefusal(nodelet, realFrame(10, 0.0)), "stamp 0");
  EXPECT_EQ(nodelet.loopDetector().map().frameCount(), 0u);
}

TEST(InputContract, PlaceServerRefusesStampZeroAndNonFiniteStamps)
{
  const Config config = shipped("gardens_point");
  PlaceServer server(config);
  EXPECT_EQ(serverRefusal(server, place("r1", 0, 0.0, config)), "stamp 0");  // even as the first frame
  server.process(place("r1", 0, 1000.0, config));
  EXPECT_EQ(serverRefusal(server, place("r1", 1, 0.0, config)), "stamp 0");
  EXPECT_EQ(serverRefusal(server, place("r1", 1, kNaN, config)), "stamp not finite");
  EXPECT_EQ(serverRefusal(server, place("r1", 1, kInf, config)), "stamp not finite");
  EXPECT_EQ(serverRefusal(server, place("r1", 1, 1.0, config)), "stamp went backwards");
  EXPECT_EQ(server.map().frameCount(), 1u);
}

// ---- finding 3: degenerate frames and place messages -----------------------------------------------------

TEST(InputContract, ImagesTooSmallToBeAPlaceAreRefused)
{
  OnlineDetector detector(shipped("default"));
  const cv::Mat real = openable_test::gardensPoint("day_right", 20);
  double stamp = 1.0;
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(100000, 1), cv::Size(1, 100000), cv::Size(15, 540)})
  {
    FrameInput input;
    cv::resize(real, input.image, size, 0, 0, cv::INTER_AREA);
    input.stamp = stamp += 1.0;
    EXPECT_EQ(frameRefusal(detector, input), "image too small") << size;
  }
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 0u);
  FrameInput small;  // 16 pixels a side is enough
  cv::resize(real, small.image, cv::Size(16, 16), 0, 0, cv::INTER_AREA);
  small.stamp = stamp += 1.0;
  EXPECT_TRUE(detector.process(small).stored);
}

TEST(InputContract, ConstantFramesAreRefusedAsPlacesUnlessIlluminationInvariant)
{
  OnlineDetector detector(shipped("default"));
  const cv::Mat real = openable_test::gardensPoint("day_right", 30);
  FrameInput black;
  black.image = cv::Mat::zeros(real.size(), real.type());
  black.stamp = 1.0;
  EXPECT_EQ(frameRefusal(detector, black), "no texture");
  FrameInput grey;
  grey.image = cv::Mat(real.size(), real.type(), cv::Scalar(128, 128, 128));
  grey.stamp = 2.0;
  EXPECT_EQ(frameRefusal(detector, grey), "no texture");
  EXPECT_THROW(detector.describe(grey), FrameRefused);
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 0u);
  // The real frame, even very dark, shows its place.
  FrameInput dark;
  dark.image = real * 0.05;
  dark.stamp = 3.0;
  EXPECT_TRUE(detector.process(dark).stored);

  Config invariant = shipped("default");
  invariant.illumination_invariance = true;
  OnlineDetector night(invariant);
  black.image = cv::Mat(real.size(), real.type(), cv::Scalar(2, 2, 2));
  EXPECT_EQ(frameRefusal(night, black), "");  // a dark frame is legitimate there
}

TEST(InputContract, NoRealNordlandFrameIsRefusedNotEvenInTunnels)
{
  // The near-black tunnel frames (mean < 10) still show a few grey levels: matched as usual.
  OnlineDetector detector(shipped("default"));
  int frames = 0;
  for (int i = 10; i <= 18000; i += 10)
  {
    char name[64];
    std::snprintf(name, sizeof(name), "nordland/summer/images-%05d.png", i);
    FrameInput input;
    input.image = cv::imread(openable_test::sharedData(name), cv::IMREAD_COLOR);
    ASSERT_FALSE(input.image.empty()) << name;
    EXPECT_NO_THROW(detector.describe(input)) << name;
    ++frames;
  }
  EXPECT_EQ(frames, 1800);
}

TEST(InputContract, ATruncatedJpegIsNotAFrame)
{
  const std::string dir = tempPath("truncated");
  std::filesystem::create_directories(dir);
  const std::string source = openable_test::sampleData("day_right/Image000.jpg");
  std::ifstream in(source, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  std::ofstream(dir + "/Image000.jpg", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::ofstream(dir + "/Image001.jpg", std::ios::binary) << bytes;
  ImageSource images(dir);
  cv::Mat image;
  std::string name;
  ASSERT_TRUE(images.next(image, name));
  EXPECT_TRUE(image.empty());
  EXPECT_NE(images.problem().find("truncated JPEG"), std::string::npos) << images.problem();
  ASSERT_TRUE(images.next(image, name));
  EXPECT_FALSE(image.empty());
  EXPECT_EQ(images.problem(), "");
}

TEST(InputContract, PlaceServerRefusesRepeatsIdsGoingBackAndForeignRobotNames)
{
  const Config config = shipped("gardens_point");
  PlaceServer server(config);
  server.process(place("robot1", 5, 100.0, config));
  EXPECT_EQ(serverRefusal(server, place("robot1", 5, 100.0, config)), "repeated message");
  EXPECT_EQ(serverRefusal(server, place("robot1", 5, 100.0, config)), "repeated message");
  EXPECT_EQ(serverRefusal(server, place("robot1", 4, 101.0, config)), "frame id went backwards");
  EXPECT_EQ(serverRefusal(server, place("robot1", 6, 100.0, config)), "stamp repeated");
  PlaceDescriptorInput foreign = place("robot2", 6, 101.0, config);
  foreign.session = "robot1";
  foreign.topic_robot = robotOfTopic("/robot1/place_descriptors");
  EXPECT_EQ(serverRefusal(server, foreign), "robot name");
  EXPECT_EQ(server.map().frameCount(), 1u);
  EXPECT_EQ(server.refused().at("repeated message"), 2u);
  PlaceDescriptorInput own = place("robot1", 6, 101.0, config);
  own.topic_robot = robotOfTopic("/robot1");
  EXPECT_TRUE(server.process(own).stored);
  EXPECT_EQ(robotOfTopic("/fleet/r2/place_descriptors"), "fleet_r2");
}

// ---- finding 6 (the small ones) ----------------------------------------------------------------------------

TEST(InputContract, AnEmptyPlaceServerSavesNoMapItsDetectorsWouldRefuse)
{
  const Config config = shipped("gardens_point");
  PlaceServer server(config);
  const std::string path = tempPath("empty_server.map");
  std::filesystem::remove(path);
  EXPECT_THROW(server.save(path), Error);
  EXPECT_FALSE(std::filesystem::exists(path));
  server.process(place("r1", 0, 10.0, config));
  server.save(path);
  EXPECT_EQ(SessionMap::load(path).frameCount(), 1u);
}
