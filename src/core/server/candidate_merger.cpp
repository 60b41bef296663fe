#include "openable/server/candidate_merger.h"

#include <algorithm>

namespace openable
{
CandidateMerger::CandidateMerger(const Config& config) : config_(config)
{
  config_.validateOrThrow();
}

uint32_t CandidateMerger::sessionIndex(const std::string& name)
{
  const auto found = indices_.find(name);
  if (found != indices_.end())
    return found->second;
  const auto index = uint32_t(names_.size());
  names_.push_back(name);
  indices_.emplace(name, index);
  return index;
}

MergedOutcome CandidateMerger::merge(std::vector<ServerCandidates> answers)
{
  if (answers.empty())
    throw Error("CandidateMerger: no server answered");
  for (const ServerCandidates& a : answers)
    if (a.query_session != answers.front().query_session || a.query_frame != answers.front().query_frame)
      throw Error("CandidateMerger: answers for different queries (session '" + a.query_session + "' frame " +
                  std::to_string(a.query_frame) + " vs session '" + answers.front().query_session + "' frame " +
                  std::to_string(answers.front().query_frame) + ")");
  // Server order fixes the order of equal distances, whatever order the answers arrived in.
  std::sort(answers.begin(), answers.end(),
            [](const ServerCandidates& a, const ServerCandidates& b) { return a.server < b.server; });

  MergedOutcome out;
  const ServerCandidates& first = answers.front();
  out.query_session = first.query_session;
  out.query_robot = first.query_robot;
  out.query_frame = first.query_frame;
  out.query_stamp = first.query_stamp;
  out.has_query_pose = first.has_query_pose;
  out.query_pose = first.query_pose;
  out.servers = answers.size();

  std::vector<ServerCandidate> all;
  size_t other_frames = 0;
  uint64_t own_first_id = 0;
  Detection& d = out.detection;
  for (const ServerCandidates& a : answers)
    d.candidates += a.candidates;
  for (const ServerCandidates& a : answers)
  {
    // A server that counts no candidate may still name a short map's early ones (MapMatcher::earlyPicks): they
    // stand only where no server has a candidate, as in one MapMatcher.
    if (a.candidates > 0 || d.candidates == 0)
      all.insert(all.end(), a.top.begin(), a.top.end());
    d.own_excluded = d.own_excluded || a.own_excluded;
    if (a.has_own_edge)  // only the server that holds the query's session cuts it
    {
      d.has_exclusion_edge = true;
      d.exclusion_edge_session = sessionIndex(out.query_session);
      d.exclusion_edge_id = a.own_edge_id;
    }
    if (a.own_short_map)
    {
      d.short_map = true;
      own_first_id = a.own_first_id;
    }
    other_frames += a.other_frames;
    if (a.stored)
    {
      out.query_stored = true;
      out.query_id = a.query_id;
    }
  }
  // Each server's list is already best first: a stable sort keeps a server's own order among equals.
  std::stable_sort(all.begin(), all.end(),
                   [](const ServerCandidate& a, const ServerCandidate& b) { return a.distance < b.distance; });
  d.query_id = out.query_id;
  sessionIndex(out.query_session);
  for (size_t i = 0; i < all.size() && i < size_t(config_.top_k); ++i)
  {
    const ServerCandidate& n = all[i];
    Candidate c;
    c.id = n.id;
    c.session = sessionIndex(n.session);
    c.distance = n.distance;
    c.direction = n.direction;
    c.shift = n.shift;
    c.sequence_length = n.sequence_length;
    d.top.push_back(c);
    out.top.push_back(n);
  }
  // As MapMatcher decides these, over the union.
  d.excluded = onlyExcludedPast(d, other_frames);
  if (!d.top.empty())
  {
    d.has_candidates = true;
    d.best = d.top.front();
    d.uniqueness =
        matchUniqueness(d.best.distance, all.size() < 2 ? std::nullopt : std::optional<float>(all[1].distance));
    d.best_at_session_start = atShortMapStart(d.best, d.short_map, sessionIndex(out.query_session), own_first_id);
  }

  auto found = streams_.find(out.query_session);
  if (found == streams_.end())
    found = streams_
                .emplace(out.query_session, StreamDecision{LoopDecision(config_),
                                                           BasicLoopConfirmation<MergedOutcome>(config_.confirm_frames)})
                .first;
  StreamDecision& stream = found->second;
  out.status = stream.decision.decide(d);
  out.score = stream.decision.score(d);
  out.confirmed = stream.confirmation.stored(out, stream.decision.joinedBefore(), stream.decision.mayJoinLater(),
                                            stream.decision.ownFramesBefore());
  return out;
}

}  // namespace openable
