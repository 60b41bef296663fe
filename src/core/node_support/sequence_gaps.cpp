#include "openable/node_support/sequence_gaps.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace openable
{
uint64_t SequenceGaps::missingFromStamps(const Input& input, double step)
{
  if (input.steps.size() < kMinSteps)
    return 0;
  // On the stack: this runs for every unnumbered frame.
  std::array<double, kStepWindow> steps{};
  const auto end = std::copy(input.steps.begin(), input.steps.end(), steps.begin());
  std::sort(steps.begin(), end);
  // The period: the typical single step, i.e. the median of the steps within 1.5x the shortest one (steps
  // under a fifth of the median are jitter or a repeated frame, not a period).
  const double median = steps[static_cast<size_t>(end - steps.begin()) / 2];
  const auto shortest = std::lower_bound(steps.begin(), end, 0.2 * median);
  const auto singles_end = std::upper_bound(shortest, end, 1.5 * *shortest);
  const double period = *(shortest + (singles_end - shortest - 1) / 2);
  // Half a period of jitter either way is still one step.
  if (!(period > 0.0) || step < 1.5 * period)
    return 0;
  return static_cast<uint64_t>(std::llround(step / period)) - 1;
}

void SequenceGaps::note(size_t index, uint32_t seq, double stamp)
{
  if (index >= inputs_.size())
    inputs_.resize(index + 1);
  Input& input = inputs_[index];
  const bool stamped = std::isfinite(stamp) && stamp > 0.0;
  const double step = stamp - input.last_stamp;
  if (input.started)
  {
    // Forward by more than one: the numbers in between were sent and never arrived. A repeat or a step back
    // (unnumbered frames, a publisher that restarted) leaves the question to the stamps.
    if (seq > input.last)
      input.lost += uint64_t(seq - input.last - 1);
    else if (stamped && step > 0.0)
      input.lost += missingFromStamps(input, step);
    if (stamped && step > 0.0)
    {
      input.steps.push_back(step);
      if (input.steps.size() > kStepWindow)
        input.steps.pop_front();
    }
    else if (stamped && step < 0.0)
    {
      input.steps.clear();  // the stamps started over: learn the period again
    }
  }
  input.started = true;
  input.last = seq;
  if (stamped)
    input.last_stamp = stamp;
}

uint64_t SequenceGaps::lost() const
{
  uint64_t most = 0;
  for (const auto& input : inputs_)
    most = std::max(most, input.lost);
  return most;
}

}  // namespace openable
