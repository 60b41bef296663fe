// readCameraCalibration: ROS camera_info YAML and KITTI calib.txt, good files and bad ones.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openable/verification/camera_calibration.h"
#include "openable/error.h"
#include "test_util.h"

namespace
{
// What camera_calibration's cameracalibrator.py writes (ost.yaml), for a 640x480 camera.
const char* kRosYaml = R"(image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [502.1, 0, 318.5, 0, 503.4, 241.2, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.29, 0.08, 0.001, -0.0002, 0]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [440.5, 0, 321.0, 0, 0, 470.25, 239.5, 0, 0, 0, 1, 0]
)";

std::string writeTemp(const std::string& name, const std::string& text)
{
  const auto path = std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

// The error of parsing `text`, which must be one line naming the file and `key`.
std::string errorOf(const std::string& text, const std::string& key)
{
  try
  {
    openable::parseCameraCalibration(text, "cam.yaml");
  }
  catch (const openable::Error& e)
  {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind("cam.yaml: ", 0), 0u) << what;
    EXPECT_NE(what.find(key), std::string::npos) << what;
    return what;
  }
  ADD_FAILURE() << "accepted: " << text;
  return "";
}
}  // namespace

TEST(CameraCalibration, RosYamlUsesTheProjectionMatrix)
{
  const auto camera = openable::readCameraCalibration(writeTemp("ost.yaml", kRosYaml));
  // Rectified images: P's intrinsics, not K's.
  EXPECT_DOUBLE_EQ(camera.fx, 440.5);
  EXPECT_DOUBLE_EQ(camera.fy, 470.25);
  EXPECT_DOUBLE_EQ(camera.cx, 321.0);
  EXPECT_DOUBLE_EQ(camera.cy, 239.5);
  EXPECT_EQ(camera.image_size, cv::Size(640, 480));
  EXPECT_FALSE(camera.stereo());
}

TEST(CameraCalibration, RosYamlWithTheCameraMatrixOnly)
{
  const std::string text = std::string(kRosYaml).substr(0, std::string(kRosYaml).find("projection_matrix"));
  const auto camera = openable::parseCameraCalibration(text, "k_only.yaml");
  EXPECT_DOUBLE_EQ(camera.fx, 502.1);
  EXPECT_DOUBLE_EQ(camera.fy, 503.4);
  EXPECT_DOUBLE_EQ(camera.cx, 318.5);
  EXPECT_DOUBLE_EQ(camera.cy, 241.2);
  // Without a size the verifier takes frames as they come.
  const auto any = openable::parseCameraCalibration(
      "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n", "k.yaml");
  EXPECT_TRUE(any.image_size.empty());
}

TEST(CameraCalibration, KittiCalibTxtIsStereoWithP1)
{
  // The real file of KITTI 07 (and of 05-10, recorded the same day).
  const auto camera = openable::readCameraCalibration(openable_test::sharedData("kitti/07_first160/calib.txt"));
  EXPECT_DOUBLE_EQ(camera.fx, 707.0912);
  EXPECT_DOUBLE_EQ(camera.fy, 707.0912);
  EXPECT_DOUBLE_EQ(camera.cx, 601.8873);
  EXPECT_DOUBLE_EQ(camera.cy, 183.1104);
  EXPECT_NEAR(camera.baseline, 0.53715, 1e-5);
  EXPECT_TRUE(camera.image_size.empty());
  const auto mono = openable::readCameraCalibration(
      writeTemp("mono_calib.txt", "P0: 700 0 600 0 0 700 180 0 0 0 1 0\r\nTr: 1 2 3 4 5 6 7 8 9 10 11 12\r\n"));
  EXPECT_FALSE(mono.stereo());
  EXPECT_DOUBLE_EQ(mono.cy, 180.0);
}

TEST(CameraCalibration, BadFilesSayWhichFileAndKey)
{
  errorOf(replaced(kRosYaml, "[440.5, 0, 321.0, 0,", "[440.5, 0, 321.0,"), "projection_matrix.data");
  EXPECT_NE(errorOf(replaced(kRosYaml, "440.5", "abc"), "projection_matrix.data").find("'abc'"), std::string::npos);
  errorOf(replaced(kRosYaml, "  rows: 3\n  cols: 4", "  rows: 4\n  cols: 4"), "projection_matrix.rows");
  errorOf(replaced(kRosYaml, "[440.5, 0", "[0, 0"), "projection_matrix");
  errorOf(replaced(kRosYaml, "image_width: 640", "image_width: -640"), "image_width");
  errorOf(replaced(kRosYaml, "image_height: 480", "image_heigth: 480"), "image_height");
  errorOf(replaced(kRosYaml, "projection_matrix:\n  rows: 3\n  cols: 4\n  data: ", "projection_matrix: "),
          "projection_matrix");
  errorOf("threshold: 0.3\nsequence_length: 30\n", "projection_matrix");  // an openable config, not a calibration
  errorOf("", "projection_matrix");
  errorOf("camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320\n", "YAML");
  errorOf("camera_matrix: {data: 5}\n", "camera_matrix.data");
  // KITTI files (read by readKittiCalibration, whose errors say "path:line: key ...").
  const std::string p0 = "P0: 700 0 600 0 0 700 180 0 0 0 1 0\n";
  const std::vector<std::pair<std::string, std::string>> kitti = {
      {"P0: 700 0 600 0 0 700 180 0 0 0 1\n", "P0"},
      {"P0: 700 0 600 0 0 700 180 0 0 0 1 x\n", "P0"},
      {"P0: 0 0 600 0 0 700 180 0 0 0 1 0\n", "P0"},
      {p0 + "P1: 700 0 600 0 0 700 180 0 0 0 1 0\n", "P1"},
      {p0 + "P1: 700 0 600 -380 0 700 180 nan 0 0 1 0\n", "P1"},
  };
  for (const auto& [text, key] : kitti)
  {
    const std::string path = writeTemp("bad_calib.txt", text);
    try
    {
      openable::readCameraCalibration(path);
      ADD_FAILURE() << "accepted: " << text;
    }
    catch (const openable::Error& e)
    {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path, 0), 0u) << what;
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  for (const std::string& path :
       {std::string("/nonexistent/calib.txt"), std::filesystem::temp_directory_path().string()})
  {
    try
    {
      openable::readCameraCalibration(path);
      ADD_FAILURE() << path;
    }
    catch (const openable::Error& e)
    {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
  }
}
