#include "openable/map/reference_map.h"

#include "openable/error.h"
#include "openable/description/frame_describer.h"

namespace openable
{
SessionMap loadReferenceMap(const std::string& path, const Config& config)
{
  const std::string refused = "map '" + path + "' refused: ";
  SessionMap map = [&]()
  {
    try
    {
      return SessionMap::load(path);
    }
    catch (const Error& e)
    {
      throw Error(refused + e.what());
    }
  }();
  if (map.configYaml().empty())
    throw Error(refused + "it carries no configuration, so its descriptors cannot be checked");
  Config map_config;
  try
  {
    map_config = Config::fromYamlString(map.configYaml());
  }
  catch (const Error& e)
  {
    throw Error(refused + "its configuration cannot be read (" + e.what() + ")");
  }
  const MapMismatch mismatch =
      mapMismatch(map_config, map.layout(), config, descriptorLayout(config), "running");
  if (!mismatch.keys.empty())
    throw Error(refused + "it was built with an incompatible configuration: " + mismatch.keys);
  if (mismatch.layout)
    throw Error(refused + "its descriptor layout differs from this detector's");
  if (map.frameCount() == 0)
    throw Error(refused + "it holds no frame; expected a map with at least one place");
  return map;
}

}  // namespace openable
