// The detector's map services (~save_map, ~load_map, ~reset): the map and the mode it is used in.
#include <memory>
#include <string>

#include "openable/error.h"
#include "openable/map/reference_map.h"
#include "openable_ros/detector.h"

namespace openable_ros
{
bool Detector::saveMap(const std::string& path, std::string& message, uint32_t& frames)
{
  std::lock_guard<std::mutex> lock(mutex_);
  try
  {
    const openable::SessionMap& map = detector_->loopDetector().map();
    map.save(path);
    frames = uint32_t(map.frameCount());
    message = "saved " + std::to_string(frames) + " frames to '" + path + "'";
    return true;
  }
  catch (const openable::Error& e)
  {
    message = "cannot save the map to '" + path + "': " + e.what();
    return false;
  }
}

bool Detector::loadMap(const std::string& path, std::string& message, uint32_t& frames)
{
  std::lock_guard<std::mutex> lock(mutex_);
  try
  {
    auto map = openable::loadReferenceMap(path, detector_->config());
    frames = uint32_t(map.frameCount());
    const size_t sessions = map.sessionCount();
    const bool continuing = parameters_.map_mode == "continue";
    auto loaded = std::make_unique<openable::OnlineDetector>(
        detector_->config(), std::move(map), continuing ? openable::MapMode::Continue : openable::MapMode::Localise,
        openable::SessionInfo{sessionName(), parameters_.robot, 0.0}, options_);
    keepCamera(*loaded);
    detector_ = std::move(loaded);
    message = "map '" + path + "' loaded: " + std::to_string(sessions) + " sessions, " + std::to_string(frames) +
              " frames; " +
              (continuing ? "continuing it as session '" + sessionName() + "'" : std::string("localising against it"));
  }
  catch (const openable::Error& e)
  {
    message = e.what();
    return false;
  }
  resetLocked();
  return true;
}

std::string Detector::sessionName() const
{
  return parameters_.session_name.empty() ? session_default_ : parameters_.session_name;
}

void Detector::keepCamera(openable::OnlineDetector& next) const
{
  if (detector_ && detector_->verifier())
    next.setCamera(detector_->verifier()->camera());
}

std::string Detector::reset()
{
  std::lock_guard<std::mutex> lock(mutex_);
  const bool had_map = detector_->localisationMode() || detector_->loopDetector().map().sessionCount() > 1;
  if (had_map)
  {
    // Back to a fresh map in loop-closure mode: the loaded map is left, the stream starts afresh (as after
    // a restart), the camera for verification is kept.
    auto fresh = freshDetector(detector_->config());
    keepCamera(*fresh);
    detector_ = std::move(fresh);
    resetLocked();
    return "map unloaded; loop-closure mode with a fresh map";
  }
  resetLocked();
  return "history cleared";
}

}  // namespace openable_ros
