#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace openable
{
/// Frames an input lost before its callback ran, from the gaps in header.seq.
///
/// roscpp drops the oldest message silently when a subscriber queue (~queue_size) or a publisher's queue
/// is full; nothing reports it. What remains visible is the publisher's numbering: roscpp numbers every
/// message a publisher sends over TCP (header.seq = 0, 1, 2, ...), so seq 7 after seq 4 means 5 and 6 were
/// published but never reached this subscriber. The count is honest only for that case:
/// - a seq that does not increase (a publisher that restarted, one that does not number its frames, e.g. a
///   nodelet in the same manager leaving seq at 0) starts counting afresh from it and adds nothing;
/// - frames lost before the first one received cannot be seen;
/// - two publishers on one topic would show their interleaving as gaps (one publisher per input assumed);
/// - a publisher that numbers frames itself (intraprocess) counts what it skipped too.
/// One counter per input (left/right, each camera of a ring); a lost set shows in every input, so the
/// frames lost are at least the largest of them: lost().
class SequenceGaps
{
public:
  /// The seq of a message that reached input `index`.
  void note(size_t index, uint32_t seq);
  /// Frames missing from the largest input's numbering.
  uint64_t lost() const;

private:
  struct Input
  {
    bool started = false;
    uint32_t last = 0;
    uint64_t lost = 0;
  };
  std::vector<Input> inputs_;
};

}  // namespace openable
