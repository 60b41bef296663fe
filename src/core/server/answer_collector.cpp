#include "openable/server/answer_collector.h"

#include <algorithm>

namespace openable
{
AnswerCollector::AnswerCollector(size_t servers, double wait) : servers_(std::max<size_t>(servers, 1)), wait_(wait) {}

void AnswerCollector::release(size_t index, std::vector<std::vector<ServerCandidates>>& out)
{
  const std::string session = pending_[index].session;
  // This query and the earlier ones of its stream (first answered earlier, so before it), oldest first.
  std::deque<Pending> kept;
  for (size_t i = 0; i < pending_.size(); ++i)
  {
    Pending& p = pending_[i];
    if (i > index || p.session != session)
    {
      kept.push_back(std::move(p));
      continue;
    }
    if (p.answers.size() < servers_)
      ++incomplete_;
    released_[p.session] = p.frame;
    any_released_[p.session] = true;
    out.push_back(std::move(p.answers));
  }
  pending_.swap(kept);
}

std::vector<std::vector<ServerCandidates>> AnswerCollector::add(ServerCandidates answer, double now)
{
  std::vector<std::vector<ServerCandidates>> out;
  const std::string& session = answer.query_session;
  // Robot frame ids grow along a stream (a server refuses stamps going back): one not newer than the last
  // released belongs to a query decided without it.
  if (any_released_[session] && answer.query_frame <= released_[session])
  {
    ++late_;
    return out;
  }
  size_t index = 0;
  while (index < pending_.size() &&
         (pending_[index].session != session || pending_[index].frame != answer.query_frame))
    ++index;
  if (index == pending_.size())
    pending_.push_back(Pending{session, answer.query_frame, now, {}});
  Pending& p = pending_[index];
  // A server answering twice (a restarted server) counts once: the newest answer stands.
  auto same = std::find_if(p.answers.begin(), p.answers.end(),
                           [&answer](const ServerCandidates& a) { return a.server == answer.server; });
  if (same != p.answers.end())
    *same = std::move(answer);
  else
    p.answers.push_back(std::move(answer));
  if (p.answers.size() >= servers_)
    release(index, out);
  return out;
}

std::vector<std::vector<ServerCandidates>> AnswerCollector::expire(double now)
{
  std::vector<std::vector<ServerCandidates>> out;
  // The oldest first; releasing one can release earlier queries of its stream too, so restart each time.
  for (size_t i = 0; i < pending_.size();)
  {
    if (now - pending_[i].first >= wait_)
    {
      release(i, out);
      i = 0;
    }
    else
      ++i;
  }
  return out;
}

}  // namespace openable
