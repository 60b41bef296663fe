#include "openable/detection/loop_confirmation.h"

#include <unordered_map>

namespace openable
{
std::vector<FrameOutcome> settled(std::vector<FrameOutcome> outcomes)
{
  std::unordered_map<uint64_t, size_t> index;  // by FrameOutcome::frame (a frame that threw has no outcome)
  for (size_t i = 0; i < outcomes.size(); ++i)
    index[outcomes[i].frame] = i;
  for (size_t i = 0; i < outcomes.size(); ++i)
  {
    std::vector<FrameOutcome> confirmed = std::move(outcomes[i].confirmed);
    outcomes[i].confirmed.clear();
    for (FrameOutcome& earlier : confirmed)
    {
      const auto found = index.find(earlier.frame);
      if (found != index.end())
        outcomes[found->second] = std::move(earlier);
    }
  }
  for (FrameOutcome& o : outcomes)
    if (o.status == FrameStatus::Pending)
      o.status = FrameStatus::Unconfirmed;
  return outcomes;
}

}  // namespace openable
