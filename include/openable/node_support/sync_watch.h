#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace openable
{
/// Watches inputs that must arrive in synchronised sets (a stereo pair, a camera ring) and says when to
/// warn: messages arrive but no complete set has been made for `timeout` seconds (they do not pair up:
/// give `advice`), or nothing ever arrived (check the topics). A stream that simply stopped is not warned
/// about, and a warning is not repeated until something new arrived. Times are seconds on any clock.
class SyncWatch
{
public:
  SyncWatch(std::vector<std::string> topics, std::string advice, double timeout, double now);

  /// One message on input `index`.
  void noteInput(size_t index);
  /// A complete set was made.
  void noteSet(double now);
  /// The warning due at `now` (empty: none), naming each topic with the messages it got since the last set.
  std::string check(double now);

  uint64_t sets() const
  {
    return sets_;
  }

private:
  std::vector<std::string> topics_;
  std::string advice_;
  double timeout_;
  double last_set_;
  uint64_t sets_ = 0;
  std::vector<uint64_t> counts_;
  std::vector<uint64_t> counts_at_last_set_;
  std::vector<uint64_t> counts_at_last_warning_;
  bool warned_ = false;
};

}  // namespace openable
