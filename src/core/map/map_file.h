#pragma once

#include <string>
#include <vector>

#include "openable/map/place_database.h"
#include "openable/map/session_map.h"

namespace openable
{
namespace map_file
{
/// One session as the writer sees it: its table entry and its frames, not copied.
struct SessionView
{
  const SessionInfo* info;
  const PlaceDatabase* frames;
};

/// Writes format 3 atomically (a temporary file in the same folder, renamed over `path`). Throws Error.
void write(const std::string& path, const DescriptorLayout& layout, const std::string& config_yaml,
           const std::vector<SessionView>& sessions);

/// Everything a map file holds. Formats 1 and 2 (before sessions) come back as one session "session 0".
struct Contents
{
  DescriptorLayout layout;
  std::string config_yaml;
  std::vector<SessionInfo> sessions;
  std::vector<PlaceDatabase> frames;
};
/// Throws Error naming what is wrong: missing, not a map, unsupported version, truncated, checksum,
/// counts that do not fit the file, an unreadable stored configuration.
Contents read(const std::string& path);

}  // namespace map_file
}  // namespace openable
