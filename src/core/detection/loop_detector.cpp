#include "openable/detection/loop_detector.h"

#include "openable/error.h"
#include "openable/description/frame_describer.h"

namespace openable
{
namespace
{
size_t capacityFor(const Config& config)
{
  return config.max_history > 0 ? static_cast<size_t>(config.max_history) : 0;
}

/// The map, checked against the configuration; a map localised against does not grow, so the room kept
/// for more frames is only memory.
SessionMap checkedMap(const Config& config, SessionMap map, MapMode mode)
{
  if (map.layout() != descriptorLayout(config))
    throw Error(
        "the map's descriptors do not match this configuration (descriptor, patch_size, grid, panoramas or "
        "camera_type differ)");
  if (mode == MapMode::Localise)
    map.shrinkToFit();
  return map;
}
}  // namespace

LoopDetector::LoopDetector(const Config& config, SessionInfo session)
  : LoopDetector(ValidConfig(config), std::move(session))
{
}

LoopDetector::LoopDetector(const ValidConfig& config, SessionInfo session)
  : LoopDetector(config, SessionMap(descriptorLayout(*config), config->toYaml()), MapMode::Continue, std::move(session))
{
}

LoopDetector::LoopDetector(const Config& config, PlaceDatabase reference_map)
  : LoopDetector(ValidConfig(config), std::move(reference_map))
{
}

LoopDetector::LoopDetector(const ValidConfig& config, PlaceDatabase reference_map)
  : LoopDetector(config, SessionMap(std::move(reference_map), SessionInfo{"session 0", "", 0.0}), MapMode::Localise)
{
}

LoopDetector::LoopDetector(const Config& config, SessionMap map, MapMode mode, SessionInfo session)
  : LoopDetector(ValidConfig(config), std::move(map), mode, std::move(session))
{
}

LoopDetector::LoopDetector(const ValidConfig& valid, SessionMap map, MapMode mode, SessionInfo session)
  : config_(*valid),
    map_(checkedMap(config_, std::move(map), mode)),
    own_session_(mode == MapMode::Continue ? static_cast<int>(map_.addSession(std::move(session), capacityFor(config_)))
                                           : -1),
    matcher_(config_, map_.layout(), mode == MapMode::Localise)
{
}

Detection LoopDetector::process(const FrameDescriptor& descriptor, FrameInfo info, const FrameDescriptor& shifted)
{
  Detection detection = matcher_.match(descriptor, map_, own_session_, info.stamp, shifted);
  if (localisationMode())
    detection.query_id = next_query_id_++;
  else
    detection.query_id = map_.add(static_cast<uint32_t>(own_session_), descriptor, std::move(info));
  return detection;
}

void LoopDetector::lastRow(std::vector<float>& out) const
{
  matcher_.lastRow(map_, out);
}

void LoopDetector::updateMatching(const Config& config)
{
  config.validateOrThrow();
  std::vector<std::string> changed;
  for (const auto& key : Config::descriptorKeys())
    if (config.get(key) != config_.get(key))
      changed.push_back(key);
  if (config.max_history != config_.max_history)
    changed.push_back("max_history");
  if (!changed.empty())
  {
    std::string keys;
    for (const auto& k : changed)
      keys += (keys.empty() ? "" : ", ") + k;
    throw Error("cannot change " + keys +
                " while running: they change the stored descriptors or history; "
                "restart the detector (the history is rebuilt from new frames)");
  }
  matcher_.setOptions(MatchOptions::from(config));
  config_ = config;
}

void LoopDetector::reset()
{
  if (!localisationMode())
    map_.clearSession(static_cast<uint32_t>(own_session_));
  matcher_.reset();
}

}  // namespace openable
