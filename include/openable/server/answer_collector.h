#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "openable/server/place_server.h"

namespace openable
{
/// Gathers the answers of several PlaceServers to the same query (same session and robot frame id) until
/// every server has answered or a bounded wait has passed, and releases them in each stream's order: a
/// LoopDecision must see a stream's frames one after another.
class AnswerCollector
{
public:
  /// `servers` answers complete a query; an incomplete one is released `wait` seconds after its first answer.
  AnswerCollector(size_t servers, double wait);

  /// Adds one answer received at `now` (seconds, any clock). Returns the queries now complete, each with its
  /// answers, oldest first; an earlier query of the same stream still waiting is released before them.
  /// An answer to a query already released (it came too late) is dropped and counted.
  std::vector<std::vector<ServerCandidates>> add(ServerCandidates answer, double now);
  /// Releases every query waiting since `now - wait` or longer (with the answers that came).
  std::vector<std::vector<ServerCandidates>> expire(double now);

  /// Queries released without every server's answer.
  size_t incomplete() const
  {
    return incomplete_;
  }
  /// Answers dropped because their query had been released already.
  size_t late() const
  {
    return late_;
  }
  size_t waiting() const
  {
    return pending_.size();
  }

private:
  struct Pending
  {
    std::string session;
    uint64_t frame = 0;
    double first = 0.0;
    std::vector<ServerCandidates> answers;
  };
  /// Releases pending_[index] and every earlier query of its stream.
  void release(size_t index, std::vector<std::vector<ServerCandidates>>& out);

  size_t servers_;
  double wait_;
  std::deque<Pending> pending_;                  ///< in order of first answer
  std::map<std::string, uint64_t> released_;     ///< per stream: the newest robot frame id released
  std::map<std::string, bool> any_released_;
  size_t incomplete_ = 0;
  size_t late_ = 0;
};

}  // namespace openable
