#include "fuzz_entries.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/detection/loop_detector.h"
#include "openable/io/npy.h"
#include "openable/map/session_map.h"

namespace openable_fuzz
{
namespace
{
/// The loaders take paths, and their size and file-type checks are part of what is tested: the bytes go
/// through a file of this process's own.
class TemporaryFile
{
public:
  TemporaryFile(const uint8_t* data, size_t size, const char* extension)
    : path_((std::filesystem::temp_directory_path() / ("openable_fuzz_" + std::to_string(::getpid()) + extension))
                .string())
  {
    FILE* file = std::fopen(path_.c_str(), "wb");
    if (!file)
      throw openable::Error("fuzz: cannot write " + path_);
    if (size > 0)
      std::fwrite(data, 1, size, file);
    std::fclose(file);
  }
  ~TemporaryFile()
  {
    std::remove(path_.c_str());
  }
  const std::string& path() const
  {
    return path_;
  }

private:
  std::string path_;
};

/// The map format ends with an FNV-1a checksum of everything before it. Random mutations would almost
/// never get past it, so the last 8 bytes are replaced by the right checksum: inputs then reach the parser
/// (the checksum check itself is covered by test_place_database).
std::string withValidChecksum(const uint8_t* data, size_t size)
{
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.size() < sizeof(uint64_t))
    return bytes;
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < body; ++i)
  {
    hash ^= static_cast<uint8_t>(bytes[i]);
    hash *= 0x100000001b3ULL;
  }
  bytes.replace(body, sizeof(uint64_t), reinterpret_cast<const char*>(&hash), sizeof(uint64_t));
  return bytes;
}

/// Uses a loaded map the way a detector would: continued as a new session, the first stored frame matched
/// against every session.
void useMap(const openable::SessionMap& map)
{
  const openable::Config config = openable::Config::fromYamlString(map.configYaml());
  if (map.frameCount() == 0 || !config.validate().empty())
    return;
  uint32_t session = 0;
  while (map.frames(session).empty())
    ++session;
  const openable::PlaceDatabase& frames = map.frames(session);
  const openable::FrameDescriptor first(frames.descriptor(0), frames.descriptor(0) + map.layout().frameWords());
  openable::LoopDetector detector(config, map, openable::MapMode::Continue, openable::SessionInfo{"fuzz", "", 0.0});
  detector.process(first);
}
}  // namespace

void loadMap(const uint8_t* data, size_t size)
{
  const std::string bytes = withValidChecksum(data, size);
  const TemporaryFile file(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), ".map");
  try
  {
    useMap(openable::SessionMap::load(file.path()));
  }
  catch (const openable::Error&)
  {
  }
}

void parseConfig(const uint8_t* data, size_t size)
{
  try
  {
    const openable::Config config =
        openable::Config::fromYamlString(std::string(reinterpret_cast<const char*>(data), size));
    if (config.validate().empty())
      openable::FrameDescriber describer(config);
  }
  catch (const openable::Error&)
  {
  }
}

void readNpy(const uint8_t* data, size_t size)
{
  const TemporaryFile file(data, size, ".npy");
  try
  {
    openable::readNpy(file.path());
  }
  catch (const openable::Error&)
  {
  }
}

}  // namespace openable_fuzz
