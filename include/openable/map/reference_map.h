#pragma once

#include <string>

#include "openable/config.h"
#include "openable/map/session_map.h"

namespace openable
{
/// Loads a saved map (every session) to localise against or continue with `config`. The map is only comparable when it was described
/// exactly as `config` describes (every key of Config::descriptorKeys() equal, same layout) and holds at
/// least one frame. Throws Error "map 'PATH' refused: <why>" naming the differing keys and both values.
SessionMap loadReferenceMap(const std::string& path, const Config& config);

}  // namespace openable
