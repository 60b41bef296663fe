#include "openable/sequence_gaps.h"

#include <algorithm>

namespace openable
{
void SequenceGaps::note(size_t index, uint32_t seq)
{
  if (index >= inputs_.size())
    inputs_.resize(index + 1);
  Input& input = inputs_[index];
  // Forward by more than one: the numbers in between were sent and never arrived. Anything else (the
  // first message, a repeat, a step back) only sets where counting goes on from.
  if (input.started && seq > input.last)
    input.lost += uint64_t(seq - input.last - 1);
  input.started = true;
  input.last = seq;
}

uint64_t SequenceGaps::lost() const
{
  uint64_t most = 0;
  for (const auto& input : inputs_)
    most = std::max(most, input.lost);
  return most;
}

}  // namespace openable
