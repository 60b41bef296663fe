#include "openable/view/trajectory_export.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "openable/error.h"

namespace openable
{
namespace
{
/// Enough digits that nothing measured is lost: 1e-9 degrees is 0.1 mm, 1e-6 m and s a micrometre/second.
std::string number(double value, int decimals)
{
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string coordinates(const GeoPosition& p)
{
  // KML order is longitude, latitude, altitude.
  return number(p.longitude, 9) + "," + number(p.latitude, 9) + "," + number(p.altitude, 3);
}

std::vector<std::string> splitCsv(const std::string& line)
{
  std::vector<std::string> fields;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');)
    fields.push_back(field);
  if (!line.empty() && line.back() == ',')
    fields.emplace_back();
  return fields;
}

bool parseNumber(const std::string& text, double& value)
{
  std::istringstream in(text);
  std::string rest;
  return static_cast<bool>(in >> value) && !(in >> rest) && std::isfinite(value);
}

void addStyle(std::ostringstream& out, const std::string& id, const std::string& kml_colour, int width)
{
  // KML colours are aabbggrr.
  out << "    <Style id=\"" << id << "\">\n"
      << "      <LineStyle><color>" << kml_colour << "</color><width>" << width << "</width></LineStyle>\n"
      << "      <IconStyle><color>" << kml_colour << "</color><scale>0.6</scale></IconStyle>\n"
      << "    </Style>\n";
}
}  // namespace

std::string geoPositionsCsvHeader()
{
  return "frame,stamp,latitude,longitude,altitude\n";
}

std::string geoPositionsCsvLine(uint64_t frame, const GeoPosition& position)
{
  return std::to_string(frame) + "," + number(position.stamp, 6) + "," + number(position.latitude, 9) + "," +
         number(position.longitude, 9) + "," + number(position.altitude, 3) + "\n";
}

std::string xmlEscape(const std::string& text)
{
  std::string out;
  out.reserve(text.size());
  for (char c : text)
  {
    switch (c)
    {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::map<int, GeoPosition> loadGeoPositions(const std::string& path)
{
  std::ifstream in(path);
  if (!in)
    throw Error("geographic positions: cannot read '" + path + "'");
  const std::string expected = "frame,stamp,latitude,longitude,altitude";
  std::map<int, GeoPosition> positions;
  std::string line;
  bool header = false;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#')
      continue;
    if (!header)
    {
      if (line != expected)
        throw Error("geographic positions: '" + path + "' line " + std::to_string(number) + " is '" + line +
                    "'; expected the header '" + expected + "'");
      header = true;
      continue;
    }
    const std::vector<std::string> fields = splitCsv(line);
    double frame = -1.0;
    GeoPosition p;
    const std::string where = "geographic positions: '" + path + "' line " + std::to_string(number);
    if (fields.size() != 5 || !parseNumber(fields[0], frame) || frame < 0 || frame != std::floor(frame) ||
        frame > 2147483647.0 || !parseNumber(fields[1], p.stamp) || !parseNumber(fields[2], p.latitude) ||
        !parseNumber(fields[3], p.longitude) || !parseNumber(fields[4], p.altitude))
      throw Error(where + " is not 'frame,stamp,latitude,longitude,altitude' (frame an integer >= 0, numbers): '" +
                  line + "'");
    if (std::abs(p.latitude) > 90.0 || std::abs(p.longitude) > 180.0)
      throw Error(where + ": latitude " + fields[2] + " / longitude " + fields[3] +
                  " out of range (expected degrees, [-90, 90] and [-180, 180])");
    if (!positions.emplace(static_cast<int>(frame), p).second)
      throw Error(where + ": frame " + fields[0] + " is given twice");
  }
  if (!header)
    throw Error("geographic positions: '" + path + "' is empty; expected the header '" + expected + "'");
  return positions;
}

std::string trajectoryCsv(const std::vector<cv::Vec3d>& positions, const std::vector<double>& stamps,
                          const std::vector<LoopPair>& loops)
{
  if (!stamps.empty() && stamps.size() != positions.size())
    throw Error("trajectory CSV: " + std::to_string(stamps.size()) + " stamps for " + std::to_string(positions.size()) +
                " positions (expected one per frame)");
  // First loop each frame closes as the query.
  std::vector<const LoopPair*> partner(positions.size(), nullptr);
  for (const LoopPair& loop : loops)
  {
    if (loop.query >= 0 && static_cast<size_t>(loop.query) < positions.size() && !partner[loop.query])
      partner[loop.query] = &loop;
  }
  std::ostringstream out;
  out << "frame,stamp,x,y,z,loop_partner,loop_agrees\n";
  for (size_t i = 0; i < positions.size(); ++i)
  {
    out << i << "," << (stamps.empty() ? "" : number(stamps[i], 6)) << "," << number(positions[i][0], 6) << ","
        << number(positions[i][1], 6) << "," << number(positions[i][2], 6) << ",";
    if (partner[i])
      out << partner[i]->match << "," << (partner[i]->agrees ? 1 : 0);
    else
      out << ",";
    out << "\n";
  }
  return out.str();
}

std::string trajectoryKml(const std::map<int, GeoPosition>& positions, const std::vector<LoopPair>& loops,
                          const std::string& name, size_t* skipped)
{
  if (positions.empty())
    throw Error("KML: no geographic positions");
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n"
      << "  <Document>\n"
      << "    <name>" << xmlEscape(name) << "</name>\n";
  addStyle(out, "trajectory", "ffb4461e", 3);
  addStyle(out, "loop_agrees", "ff00aa00", 4);
  addStyle(out, "loop_disagrees", "ff0000e6", 4);
  out << "    <Placemark>\n"
      << "      <name>trajectory</name>\n"
      << "      <description>" << positions.size() << " frames, " << positions.begin()->first << " to "
      << positions.rbegin()->first << "</description>\n"
      << "      <styleUrl>#trajectory</styleUrl>\n"
      << "      <LineString>\n"
      << "        <tessellate>1</tessellate>\n"
      << "        <coordinates>\n";
  for (const auto& entry : positions)
    out << "          " << coordinates(entry.second) << "\n";
  out << "        </coordinates>\n"
      << "      </LineString>\n"
      << "    </Placemark>\n"
      << "    <Folder>\n"
      << "      <name>loop closures</name>\n";
  size_t left_out = 0;
  for (const LoopPair& loop : loops)
  {
    const auto query = positions.find(loop.query), match = positions.find(loop.match);
    if (query == positions.end() || match == positions.end())
    {
      ++left_out;
      continue;
    }
    out << "      <Placemark>\n"
        << "        <name>loop " << loop.query << " - " << loop.match << "</name>\n"
        << "        <description>frame " << loop.query << " recognised as the place of frame " << loop.match
        << "; ground truth " << (loop.agrees ? "agrees" : "disagrees") << "</description>\n"
        << "        <styleUrl>#" << (loop.agrees ? "loop_agrees" : "loop_disagrees") << "</styleUrl>\n"
        << "        <MultiGeometry>\n"
        << "          <Point><coordinates>" << coordinates(query->second) << "</coordinates></Point>\n"
        << "          <LineString><tessellate>1</tessellate><coordinates>" << coordinates(query->second) << " "
        << coordinates(match->second) << "</coordinates></LineString>\n"
        << "        </MultiGeometry>\n"
        << "      </Placemark>\n";
  }
  out << "    </Folder>\n"
      << "  </Document>\n"
      << "</kml>\n";
  if (skipped)
    *skipped = left_out;
  return out.str();
}

}  // namespace openable
