#include "openable/detection/loop_confirmation.h"

#include <string>

#include "openable/error.h"

namespace openable
{
LoopConfirmation::LoopConfirmation(int frames) : frames_(0)
{
  setFrames(frames);
}

void LoopConfirmation::setFrames(int frames)
{
  if (frames < 0)
    throw Error("confirm_frames " + std::to_string(frames) + " is out of range; expected frames >= 0");
  frames_ = frames;
  reset();
}

void LoopConfirmation::reset()
{
  waiting_.clear();
}

size_t LoopConfirmation::pending() const
{
  size_t count = 0;
  for (const Waiting& w : waiting_)
    count += w.outcomes.size();
  return count;
}

std::vector<FrameOutcome> LoopConfirmation::stored(FrameOutcome& outcome)
{
  std::vector<FrameOutcome> confirmed;
  if (frames_ == 0)
    return confirmed;
  if (!outcome.published())
  {
    // The run ended (or never was): what waited for it is not confirmed.
    waiting_.clear();
    return confirmed;
  }
  for (Waiting& w : waiting_)
    ++w.confirmations;
  while (!waiting_.empty() && waiting_.front().confirmations >= frames_)
  {
    for (FrameOutcome& o : waiting_.front().outcomes)
    {
      o.status = FrameStatus::Published;
      confirmed.push_back(std::move(o));
    }
    waiting_.pop_front();
  }
  outcome.status = FrameStatus::Pending;
  waiting_.push_back(Waiting{{outcome}, 0});
  return confirmed;
}

void LoopConfirmation::repeated(const FrameOutcome& outcome)
{
  if (outcome.status != FrameStatus::Pending || waiting_.empty())
    return;
  std::vector<FrameOutcome>& outcomes = waiting_.back().outcomes;
  if (outcomes.size() <= kMaxRepeats)
    outcomes.push_back(outcome);
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
