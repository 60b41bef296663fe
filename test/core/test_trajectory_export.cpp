// Trajectory CSV, geographic positions and the KML export (checked as XML by python3's xml.etree).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "openable/error.h"
#include "openable/view/trajectory_export.h"

#ifndef PYTHON3_EXECUTABLE
#error "PYTHON3_EXECUTABLE must be defined by the build"
#endif

namespace fs = std::filesystem;
using openable::GeoPosition;
using openable::LoopPair;

namespace
{
fs::path tempPath(const std::string& name)
{
  return fs::temp_directory_path() / ("openable_trajectory_export_" + std::to_string(::getpid()) + "_" + name);
}

std::string writeFile(const std::string& name, const std::string& text)
{
  const fs::path path = tempPath(name);
  std::ofstream(path) << text;
  return path.string();
}

/// Runs test/core/check_kml.py on `kml`; returns its exit status and puts its output in `report`.
int checkKml(const std::string& kml, int path_points, int loops, int agree, std::string& report)
{
  const std::string file = writeFile("check.kml", kml);
  const std::string log = tempPath("check.log").string();
  const std::string command = std::string(PYTHON3_EXECUTABLE) + " '" + OPENABLE_SOURCE_DIR +
                              "/test/core/check_kml.py' '" + file + "' " + std::to_string(path_points) + " " +
                              std::to_string(loops) + " " + std::to_string(agree) + " >'" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  report.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A short walk around a block in Almeria (made up): five frames, back near the start.
std::map<int, GeoPosition> walk()
{
  std::map<int, GeoPosition> p;
  p[0] = {36.8381, -2.4597, 12.0, 0.0};
  p[1] = {36.8385, -2.4597, 12.5, 1.0};
  p[2] = {36.8385, -2.4590, 13.0, 2.0};
  p[3] = {36.8381, -2.4590, 12.5, 3.0};
  p[4] = {36.83811, -2.45969, 12.0, 4.0};
  return p;
}
}  // namespace

TEST(TrajectoryExport, CsvHasOneLinePerFrameWithItsLoopPartner)
{
  const std::vector<cv::Vec3d> positions = {{0, 0, 0}, {1.5, -0.25, 10}, {0.1, 0, 0.2}};
  std::vector<LoopPair> loops = {{2, 0}, {2, 1}};  // the first loop of frame 2 is its partner
  loops[0].agrees = true;
  EXPECT_EQ(openable::trajectoryCsv(positions, {100.0, 100.1, 100.2}, loops),
            "frame,stamp,x,y,z,loop_partner,loop_agrees\n"
            "0,100.000000,0.000000,0.000000,0.000000,,\n"
            "1,100.100000,1.500000,-0.250000,10.000000,,\n"
            "2,100.200000,0.100000,0.000000,0.200000,0,1\n");
  EXPECT_EQ(openable::trajectoryCsv(positions, {}, {}).substr(0, 60),
            "frame,stamp,x,y,z,loop_partner,loop_agrees\n0,,0.000000,0.000");
  EXPECT_THROW(openable::trajectoryCsv(positions, {1.0}, {}), openable::Error);
}

TEST(TrajectoryExport, GeoPositionsFromCsv)
{
  const auto p = openable::loadGeoPositions(
      writeFile("geo.csv",
                "frame,stamp,latitude,longitude,altitude\n0,1.5,36.8381,-2.4597,12\r\n\n2,1.7,36.8382,-2.4598,12.5\n"));
  ASSERT_EQ(p.size(), 2u);
  EXPECT_DOUBLE_EQ(p.at(2).latitude, 36.8382);
  EXPECT_DOUBLE_EQ(p.at(2).longitude, -2.4598);
  EXPECT_DOUBLE_EQ(p.at(2).altitude, 12.5);
  EXPECT_DOUBLE_EQ(p.at(0).stamp, 1.5);
  const std::string header = "frame,stamp,latitude,longitude,altitude\n";
  for (const std::string& bad :
       {std::string("frame,lat,lon\n0,1,2\n"), header + "0,1,95,2,3\n", header + "0,1,36,190,3\n",
        header + "0,1,36,2\n", header + "1.5,1,36,2,3\n", header + "0,1,36,2,3\n0,2,36,2,3\n", std::string("")})
    EXPECT_THROW(openable::loadGeoPositions(writeFile("bad.csv", bad)), openable::Error) << bad;
  EXPECT_THROW(openable::loadGeoPositions("/nonexistent/geo.csv"), openable::Error);
}

TEST(TrajectoryExport, KmlIsValidXmlWithThePathAndOnePlacemarkPerLoop)
{
  std::vector<LoopPair> loops = {{4, 0}, {3, 1}, {9, 0}};  // 9 has no position: left out
  loops[0].agrees = true;
  size_t skipped = 0;
  const std::string kml = openable::trajectoryKml(walk(), loops, "walk <around> & \"back\"", &skipped);
  EXPECT_EQ(skipped, 1u);
  std::string report;
  EXPECT_EQ(checkKml(kml, 5, 2, 1, report), 0) << report << kml;
  EXPECT_NE(kml.find("<name>walk &lt;around&gt; &amp; &quot;back&quot;</name>"), std::string::npos);
  EXPECT_NE(kml.find("-2.459700000,36.838100000,12.000"), std::string::npos);  // lon,lat,alt
  // The checker is strict: a wrong count or broken XML fails it.
  EXPECT_NE(checkKml(kml, 5, 3, 1, report), 0);
  EXPECT_NE(checkKml(kml.substr(0, kml.size() - 8), 5, 2, 1, report), 0);
  EXPECT_THROW(openable::trajectoryKml({}, loops, "empty"), openable::Error);
}

TEST(TrajectoryExport, XmlEscape)
{
  EXPECT_EQ(openable::xmlEscape("a<b>&'c\""), "a&lt;b&gt;&amp;&apos;c&quot;");
  EXPECT_EQ(openable::xmlEscape("plain"), "plain");
}
