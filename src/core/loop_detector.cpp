#include "openable/loop_detector.h"

#include <algorithm>
#include <cmath>

#include "openable/error.h"
#include "openable/frame_describer.h"

namespace openable
{
namespace
{
DescriptorLayout layoutFor(const Config& config)
{
  return FrameDescriber(config).layout();
}

size_t capacityFor(const Config& config)
{
  return config.max_history > 0 ? static_cast<size_t>(config.max_history) : 0;
}
}  // namespace

LoopDetector::LoopDetector(const Config& config)
  : config_(config),
    localisation_(false),
    database_(layoutFor(config), capacityFor(config), config.toYaml()),
    matcher_(database_.layout(), config.sequence_length, config.bidirectional),
    metric_(database_.layout())
{
}

LoopDetector::LoopDetector(const Config& config, PlaceDatabase reference_map)
  : config_(config),
    localisation_(true),
    database_(std::move(reference_map)),
    matcher_(database_.layout(), config.sequence_length, config.bidirectional),
    metric_(database_.layout())
{
  config.validateOrThrow();
  // A reference map does not grow in localisation: the room kept for more frames is only memory.
  database_.shrinkToFit();
  if (database_.layout() != layoutFor(config))
    throw Error(
        "the reference map's descriptors do not match this configuration (descriptor, patch_size, grid, "
        "panoramas or camera_type differ)");
}

int LoopDetector::minTerms() const
{
  if (!localisation_ || config_.min_sequence_length == 0)
    return config_.sequence_length;
  return config_.min_sequence_length;
}

size_t LoopDetector::candidateColumns(double stamp) const
{
  if (localisation_)
    return database_.size();
  const size_t excluded = static_cast<size_t>(config_.exclusion_window);
  size_t columns = database_.size() > excluded ? database_.size() - excluded : 0;
  if (config_.exclusion_seconds > 0.0 && stamp > 0.0)
  {
    // Stamps grow along the history (the caller refuses time jumps): the first position stamped too
    // recently, by binary search.
    const double newest_allowed = stamp - config_.exclusion_seconds;
    size_t low = 0, high = columns;
    while (low < high)
    {
      const size_t middle = low + (high - low) / 2;
      if (database_.stamp(middle) > newest_allowed)
        high = middle;
      else
        low = middle + 1;
    }
    columns = low;
  }
  return columns;
}

Candidate LoopDetector::candidateAt(size_t column) const
{
  Candidate c;
  int direction = 1;
  c.distance = matcher_.normalized(column, &direction, minTerms());
  c.direction = static_cast<int8_t>(direction);
  c.id = matcher_.firstId() + column;
  c.position = static_cast<size_t>(c.id - database_.firstId());
  c.sequence_length = direction > 0 ? matcher_.forwardCount(column) : matcher_.reverseCount(column);
  if (database_.layout().blocks > 1)
  {
    int shift = 0;
    metric_.distance(last_query_.data(), database_.descriptor(c.position), &shift);
    c.shift = static_cast<int16_t>(shift);
  }
  return c;
}

Detection LoopDetector::process(const FrameDescriptor& descriptor, FrameInfo info)
{
  if (descriptor.size() != static_cast<size_t>(database_.layout().frameWords()))
    throw Error("descriptor of " + std::to_string(descriptor.size()) + " words does not fit the detector's " +
                std::to_string(database_.layout().frameWords()) + " words");
  last_query_ = descriptor;
  Detection detection;
  const size_t columns = candidateColumns(info.stamp);
  matcher_.match(descriptor.data(), database_, columns);

  // Top-k distinct places: repeatedly the smallest distance outside the windows of those already taken.
  // The matcher answers from what it summarised while matching: no second pass over the row.
  const size_t wanted = static_cast<size_t>(std::max(config_.top_k, 2));
  std::vector<size_t> taken;
  detection.candidates =
      matcher_.smallestDistinct(wanted, static_cast<size_t>(std::max(0, config_.uniqueness_window)), minTerms(), taken);
  for (size_t i = 0; i < taken.size() && i < static_cast<size_t>(config_.top_k); ++i)
    detection.top.push_back(candidateAt(taken[i]));

  detection.excluded = detection.top.empty() && !localisation_ && !database_.empty() && columns == 0;
  if (!detection.top.empty())
  {
    detection.has_candidates = true;
    detection.best = detection.top.front();
    if (taken.size() < 2)
      detection.uniqueness = 1.0f;
    else
    {
      const float second = matcher_.normalized(taken[1], nullptr, minTerms());
      detection.uniqueness = second > 0.0f ? 1.0f - detection.best.distance / second : 0.0f;
    }
    // At least one gate must be on: with neither a threshold nor a uniqueness bound, nothing is accepted.
    const bool gated = config_.threshold >= 0.0 || config_.min_uniqueness > 0.0;
    detection.accepted = gated && (config_.threshold < 0.0 || detection.best.distance <= config_.threshold) &&
                         detection.uniqueness >= config_.min_uniqueness;
  }

  if (localisation_)
    detection.query_id = next_query_id_++;
  else
    detection.query_id = database_.add(descriptor, std::move(info));
  return detection;
}

void LoopDetector::lastRow(std::vector<float>& out) const
{
  out.assign(database_.size(), std::nanf(""));
  for (size_t c = 0; c < matcher_.columns(); ++c)
  {
    const uint64_t id = matcher_.firstId() + c;
    if (id < database_.firstId())
      continue;  // evicted after matching
    const size_t position = static_cast<size_t>(id - database_.firstId());
    if (position < out.size())
      out[position] = matcher_.normalized(c, nullptr, minTerms());
  }
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
  if (config.sequence_length != config_.sequence_length)
    matcher_.setSequenceLength(config.sequence_length);
  if (config.bidirectional != config_.bidirectional)
    matcher_.setBidirectional(config.bidirectional);
  config_ = config;
}

void LoopDetector::reset()
{
  if (!localisation_)
    database_.clear();
  matcher_.reset();
}

}  // namespace openable
