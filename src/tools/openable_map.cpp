// openable_map: what a saved map holds, maps merged, a map exported as CSV; see --help.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "openable/io/atomic_file.h"
#include "openable/config.h"
#include "openable/error.h"
#include "openable/detection/map_replay.h"
#include "openable/map/session_map.h"
#include "openable/io/staged_output.h"

namespace
{
namespace fs = std::filesystem;
using openable::Error;

const char kUsage[] = R"(openable_map: what a saved map holds, maps merged, a map exported as CSV.

Usage:
  openable_map info MAP                 sessions (name, robot, frames, ids, start stamp), configuration, bytes
  openable_map merge A B -o C           C holds A's sessions, then B's (their ids renumbered after A's); both
                                        must be described with the same configuration, share no session name
                                        and hold frames (an empty map is refused, as --map-in refuses it)
  openable_map export MAP --csv DIR     DIR/frames.csv: session,session_name,id,stamp,source,has_pose,x,y,z,qx,qy,qz,qw
                                        DIR/loop_closures.csv: query_session,query,match_session,match,distance,score
                                        (the loops a run continuing the sessions one after another publishes,
                                        replayed from the stored descriptors with the map's configuration)

MAP files are written by openable_offline --map-out, the detectors' ~save_map and PlaceServer.
Exit status: 0 on success, 1 with a one-line reason on stderr for bad input, 2 for bad usage.
)";

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// A CSV field: quoted (quotes doubled) when it holds a comma, a quote or a line break.
std::string csvField(const std::string& text)
{
  if (text.find_first_of(",\"\n") == std::string::npos)
    return text;
  std::string quoted = "\"";
  for (char c : text)
    quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string sixDecimals(double stamp)
{
  std::ostringstream out;
  out << std::fixed << std::setprecision(6) << stamp;
  return out.str();
}

int info(const std::string& path)
{
  const openable::SessionMap map = openable::SessionMap::load(path);
  std::cout << "map: " << path << "\n"
            << "sessions: " << map.sessionCount() << "\n"
            << "frames: " << map.frameCount() << "\n"
            << "descriptor bytes per frame: " << sizeof(uint64_t) * map.layout().frameWords() << "\n"
            << "bytes in memory: " << map.bytes() << "\n"
            << "bytes on disk: " << fs::file_size(path) << "\n";
  for (uint32_t s = 0; s < map.sessionCount(); ++s)
  {
    const openable::PlaceDatabase& frames = map.frames(s);
    std::cout << "session " << s << ": '" << map.session(s).name << "'"
              << (map.session(s).robot.empty() ? "" : " robot '" + map.session(s).robot + "'") << ", "
              << frames.size() << " frames";
    if (!frames.empty())
      std::cout << ", ids " << frames.firstId() << ".." << frames.firstId() + frames.size() - 1;
    std::cout << ", start stamp " << sixDecimals(map.session(s).start_stamp) << "\n";
  }
  std::cout << "configuration:\n" << map.configYaml();
  if (!map.configYaml().empty() && map.configYaml().back() != '\n')
    std::cout << "\n";
  return 0;
}

/// A map with at least one frame: what --map-in and the detectors accept (an empty one they refuse).
openable::SessionMap loadWithFrames(const std::string& path)
{
  openable::SessionMap map = openable::SessionMap::load(path);
  if (map.frameCount() == 0)
    throw Error("map '" + path + "' holds no frame (" + std::to_string(map.sessionCount()) +
                " sessions); --map-in and the detectors refuse such a map: expected a map with at least one place");
  return map;
}

int merge(const std::string& a, const std::string& b, const std::string& out)
{
  const openable::SessionMap merged = openable::SessionMap::merge(loadWithFrames(a), loadWithFrames(b));
  merged.save(out);
  std::cout << "merged " << a << " and " << b << " into " << out << ": " << merged.sessionCount() << " sessions, "
            << merged.frameCount() << " frames\n";
  return 0;
}

int exportCsv(const std::string& path, const std::string& dir)
{
  const openable::SessionMap map = openable::SessionMap::load(path);
  if (map.configYaml().empty())
    throw Error("map '" + path + "' carries no configuration, so its loop closures cannot be replayed");
  const openable::Config config = openable::Config::fromYamlString(map.configYaml());
  openable::StagedOutput output(dir, "openable_map_export");

  std::ostringstream frames;
  frames << "session,session_name,id,stamp,source,has_pose,x,y,z,qx,qy,qz,qw\n";
  for (uint32_t s = 0; s < map.sessionCount(); ++s)
    for (size_t p = 0; p < map.frames(s).size(); ++p)
    {
      const openable::FrameInfo f = map.frames(s).info(p);
      frames << s << "," << csvField(map.session(s).name) << "," << f.id << "," << sixDecimals(f.stamp) << ","
             << csvField(f.source)
             << "," << (f.has_pose ? 1 : 0);
      for (double v : f.pose)
        frames << "," << (f.has_pose ? sixDecimals(v) : "");  // micrometres, and quaternions to 1e-6
      frames << "\n";
    }
  const std::vector<openable::MapLoop> loops = openable::replayLoops(map, config);
  std::ostringstream csv;
  csv << "query_session,query,match_session,match,distance,score\n";
  for (const openable::MapLoop& loop : loops)
    csv << loop.query_session << "," << loop.query_id << "," << loop.match_session << "," << loop.match_id << ","
        << loop.distance << "," << loop.score << "\n";
  openable::writeFileAtomically(output.path("frames.csv"), frames.str());
  openable::writeFileAtomically(output.path("loop_closures.csv"), csv.str());
  output.publish();
  std::cout << "exported " << map.frameCount() << " frames of " << map.sessionCount() << " sessions and "
            << loops.size() << " loop closures to " << dir << "/{frames.csv,loop_closures.csv}\n";
  return 0;
}

int run(const std::vector<std::string>& args)
{
  if (args.empty() || args[0] == "--help" || args[0] == "-h")
  {
    if (args.empty())
      throw UsageError("a command is needed: info, merge or export");
    std::cout << kUsage;
    return 0;
  }
  const std::string& command = args[0];
  if (command == "info" && args.size() == 2)
    return info(args[1]);
  if (command == "merge" && args.size() == 5 && args[3] == "-o")
    return merge(args[1], args[2], args[4]);
  if (command == "export" && args.size() == 4 && args[2] == "--csv")
    return exportCsv(args[1], args[3]);
  if (command != "info" && command != "merge" && command != "export")
    throw UsageError("unknown command '" + command + "'; expected info, merge or export");
  throw UsageError("wrong arguments for '" + command + "'");
}
}  // namespace

int main(int argc, char** argv)
{
  try
  {
    return run(std::vector<std::string>(argv + 1, argv + argc));
  }
  catch (const UsageError& e)
  {
    std::cerr << "openable_map: " << e.what() << " (see --help)\n";
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "openable_map: " << e.what() << "\n";
    return 1;
  }
}
