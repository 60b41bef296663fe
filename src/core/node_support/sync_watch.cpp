#include "openable/node_support/sync_watch.h"

#include <sstream>

namespace openable
{
SyncWatch::SyncWatch(std::vector<std::string> topics, std::string advice, double timeout, double now)
  : topics_(std::move(topics)),
    advice_(std::move(advice)),
    timeout_(timeout),
    last_set_(now),
    counts_(topics_.size(), 0),
    counts_at_last_set_(topics_.size(), 0),
    counts_at_last_warning_(topics_.size(), 0)
{
}

void SyncWatch::noteInput(size_t index)
{
  if (index < counts_.size())
    ++counts_[index];
}

void SyncWatch::noteSet(double now)
{
  ++sets_;
  last_set_ = now;
  counts_at_last_set_ = counts_;
  warned_ = false;
}

std::string SyncWatch::check(double now)
{
  const double quiet = now - last_set_;
  if (timeout_ <= 0.0 || quiet < timeout_)
    return "";
  uint64_t since_set = 0, total = 0;
  std::ostringstream counts;
  for (size_t i = 0; i < topics_.size(); ++i)
  {
    const uint64_t n = counts_[i] - counts_at_last_set_[i];
    counts << (i ? "," : "") << " '" << topics_[i] << "' " << n;
    since_set += n;
    total += counts_[i];
  }
  // A stream that stopped after working stays silent; and once warned, only new messages warn again.
  if (since_set == 0 && total > 0)
    return "";
  if (warned_ && counts_ == counts_at_last_warning_ && total > 0)
    return "";
  warned_ = true;
  counts_at_last_warning_ = counts_;
  std::ostringstream what;
  what << "no synchronised input set for " << int(quiet) << " s (" << sets_
       << " sets so far). Received since the last set:" << counts.str() << " messages.";
  what << " " << (since_set > 0 ? advice_ : std::string("Check that the topics are published and remapped."));
  return what.str();
}

}  // namespace openable
