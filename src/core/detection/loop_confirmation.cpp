#include "openable/detection/loop_confirmation.h"

#include <cmath>
#include <cstdlib>
#include <unordered_map>

namespace openable
{
void placeInHindsight(std::vector<FrameOutcome>& confirmed, const FrameOutcome& confirming)
{
  const Detection& now = confirming.detection;
  if (!now.has_candidates || now.best.direction != 1)
    return;
  for (FrameOutcome& c : confirmed)
  {
    Candidate& then = c.detection.best;
    const uint64_t back = now.query_id - c.detection.query_id;
    if (!c.detection.has_candidates || then.session != now.best.session || then.direction != 1 ||
        then.pace == now.best.pace || now.query_id <= c.detection.query_id || back > kHindsightFrames)
      continue;
    const long expected = static_cast<long>(now.best.id) - std::lround(now.best.pace * static_cast<double>(back));
    const long delta = expected - static_cast<long>(then.id);
    if (std::labs(delta) < kHindsightMin || std::labs(delta) > kHindsightMax || static_cast<long>(then.position) + delta < 0)
      continue;
    then.id = static_cast<uint64_t>(static_cast<long>(then.id) + delta);
    then.position = static_cast<size_t>(static_cast<long>(then.position) + delta);
    c.has_match_info = false;
  }
}

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
