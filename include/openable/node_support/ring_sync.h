#pragma once

#include <cmath>
#include <cstddef>
#include <deque>
#include <functional>
#include <vector>

namespace openable
{
/// Synchronises a runtime number of inputs (a camera ring), which message_filters' fixed-arity
/// Synchronizer cannot. A set is complete when every input has an item whose stamp is within `max_skew`
/// seconds of the newest arrival (0 = identical stamps). Each input keeps at most `queue_size` items;
/// older ones are dropped, and every item at or before a completed set's is discarded with it.
/// `Item` is anything with a stamp (a message pointer in the ROS layer, a number in tests).
template <typename Item>
class RingSync
{
public:
  using Stamp = std::function<double(const Item&)>;
  using Set = std::vector<Item>;

  RingSync(size_t inputs, size_t queue_size, double max_skew, Stamp stamp)
    : queues_(inputs),
      queue_size_(queue_size == 0 ? 1 : queue_size),
      max_skew_(max_skew < 0.0 ? 0.0 : max_skew),
      stamp_(std::move(stamp))
  {
  }

  /// Adds input `index`'s item; returns true and fills `set` (input order) when it completes a set.
  bool add(size_t index, const Item& item, Set& set)
  {
    if (index >= queues_.size())
      return false;
    auto& queue = queues_[index];
    queue.push_back(item);
    while (queue.size() > queue_size_)
    {
      queue.pop_front();
      ++dropped_;
    }
    // The new item can only complete a set that contains it: look for its partners.
    const double reference = stamp_(item);
    std::vector<size_t> chosen(queues_.size(), 0);
    for (size_t c = 0; c < queues_.size(); ++c)
    {
      double best = -1.0;
      for (size_t i = 0; i < queues_[c].size(); ++i)
      {
        const double skew = std::fabs(stamp_(queues_[c][i]) - reference);
        if (skew <= max_skew_ + 1e-9 && (best < 0.0 || skew < best))
        {
          best = skew;
          chosen[c] = i;
        }
      }
      if (best < 0.0)
        return false;
    }
    set.clear();
    for (size_t c = 0; c < queues_.size(); ++c)
    {
      set.push_back(queues_[c][chosen[c]]);
      queues_[c].erase(queues_[c].begin(), queues_[c].begin() + long(chosen[c]) + 1);
    }
    return true;
  }

  /// Items dropped without ever being part of a set (queue overflow).
  size_t dropped() const
  {
    return dropped_;
  }

private:
  std::vector<std::deque<Item>> queues_;
  size_t queue_size_;
  double max_skew_;
  Stamp stamp_;
  size_t dropped_ = 0;
};

}  // namespace openable
