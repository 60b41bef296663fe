#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace openable
{
/// Frames an input lost before its callback ran, from the gaps in header.seq or, where seq says nothing,
/// in the stamps.
///
/// roscpp drops the oldest message silently when a subscriber queue (~queue_size) or a publisher's queue
/// is full; nothing reports it. What remains visible:
/// - The publisher's numbering: roscpp numbers every message a publisher sends over TCP (header.seq = 0, 1,
///   2, ...), so seq 7 after seq 4 means 5 and 6 were published but never reached this subscriber.
/// - Where seq does not increase (a bag converted with seq 0, rosbag play republishing it, a nodelet in the
///   same manager), the stamps: a camera stamps its frames at a steady period, so a step of about k periods
///   means k - 1 frames missing. The period is the typical single step between recent frames (the median of
///   the steps within 1.5x the shortest; steps under a fifth of the median are ignored), learnt while frames
///   arrive one after another (the detector is idle at the start of a stream); until kMinSteps steps are
///   known nothing is counted. This counts what the camera itself skipped too, a camera with an irregular
///   rate may show gaps it did not have, and in a long overload where no frame arrives right after the one
///   before, the period is overestimated (fewer counted); a stamp that goes back starts learning afresh.
/// - Frames lost before the first one received cannot be seen; two publishers on one topic would show their
///   interleaving as gaps (one publisher per input assumed).
/// One counter per input (left/right, each camera of a ring); a lost set shows in every input, so the
/// frames lost are at least the largest of them: lost().
class SequenceGaps
{
public:
  /// Steps between stamps needed before stamp gaps are counted.
  static constexpr size_t kMinSteps = 8;
  /// Recent steps the period is estimated from.
  static constexpr size_t kStepWindow = 64;

  /// The seq and stamp (seconds) of a message that reached input `index`.
  void note(size_t index, uint32_t seq, double stamp);
  /// Frames missing from the largest input's numbering (or stamps).
  uint64_t lost() const;

private:
  struct Input
  {
    bool started = false;
    uint32_t last = 0;
    double last_stamp = 0.0;
    uint64_t lost = 0;
    std::deque<double> steps;  ///< recent steps between stamps (seconds), newest last
  };
  /// Frames missing between two stamps `step` seconds apart (0 while the period is unknown).
  static uint64_t missingFromStamps(const Input& input, double step);
  std::vector<Input> inputs_;
};

}  // namespace openable
