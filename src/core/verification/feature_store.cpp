// The features kept for history frames and their memory bound (FrameFeatures, FeatureStore).
#include <algorithm>
#include <cmath>

#include "openable/verification/geometric_verifier.h"

namespace openable
{
size_t FrameFeatures::depthCount() const
{
  size_t count = 0;
  for (const auto& p : points)
    count += std::isfinite(p.z) ? 1 : 0;
  return count;
}

size_t FrameFeatures::bytes() const
{
  return sizeof(FrameFeatures) + keypoints.capacity() * sizeof(cv::KeyPoint) +
         descriptors.total() * descriptors.elemSize() + points.capacity() * sizeof(cv::Point3f);
}

FeatureStore::FeatureStore(size_t max_bytes) : max_bytes_(max_bytes) {}

void FeatureStore::insert(FrameFeatures features)
{
  const size_t size = features.bytes();
  if (size > max_bytes_)
    return;
  const uint64_t id = features.id;
  auto it = frames_.find(id);
  if (it != frames_.end())
  {
    bytes_ -= it->second.bytes();
    it->second = std::move(features);
  }
  else
  {
    frames_.emplace(id, std::move(features));
  }
  order_.push_back(id);
  bytes_ += size;
  evict();
}

void FeatureStore::evict()
{
  while (bytes_ > max_bytes_ && !order_.empty())
  {
    const uint64_t id = order_.front();
    order_.pop_front();
    // A replaced frame appears twice in order_; only its last occurrence owns it.
    if (std::find(order_.begin(), order_.end(), id) != order_.end())
      continue;
    auto it = frames_.find(id);
    if (it == frames_.end())
      continue;
    bytes_ -= it->second.bytes();
    frames_.erase(it);
    ++evicted_;
  }
}

const FrameFeatures* FeatureStore::find(uint64_t id) const
{
  auto it = frames_.find(id);
  return it == frames_.end() ? nullptr : &it->second;
}

void FeatureStore::clear()
{
  frames_.clear();
  order_.clear();
  bytes_ = 0;
}

}  // namespace openable
