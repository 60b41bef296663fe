#include "openable_ros/ring_synchronizer.h"

#include <cmath>

namespace openable_ros
{
RingSynchronizer::RingSynchronizer(size_t cameras, size_t queue_size, double max_skew)
  : queues_(cameras), queue_size_(queue_size == 0 ? 1 : queue_size), max_skew_(max_skew < 0.0 ? 0.0 : max_skew)
{
}

bool RingSynchronizer::add(size_t camera, const sensor_msgs::ImageConstPtr& image, Set& set)
{
  if (camera >= queues_.size())
  {
    return false;
  }
  auto& queue = queues_[camera];
  queue.push_back(image);
  while (queue.size() > queue_size_)
  {
    queue.pop_front();
    ++dropped_;
  }

  // The new image can only complete a set that contains it: look for its partners.
  const ros::Time reference = image->header.stamp;
  std::vector<size_t> chosen(queues_.size(), 0);
  for (size_t c = 0; c < queues_.size(); ++c)
  {
    double best = -1.0;
    for (size_t i = 0; i < queues_[c].size(); ++i)
    {
      const double skew = std::fabs((queues_[c][i]->header.stamp - reference).toSec());
      if (skew <= max_skew_ + 1e-9 && (best < 0.0 || skew < best))
      {
        best = skew;
        chosen[c] = i;
      }
    }
    if (best < 0.0)
    {
      return false;
    }
  }
  set.assign(queues_.size(), nullptr);
  for (size_t c = 0; c < queues_.size(); ++c)
  {
    set[c] = queues_[c][chosen[c]];
    // Everything up to the chosen image can never be part of a later set.
    queues_[c].erase(queues_[c].begin(), queues_[c].begin() + long(chosen[c]) + 1);
  }
  return true;
}

}  // namespace openable_ros
