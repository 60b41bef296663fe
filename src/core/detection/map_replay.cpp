#include "openable/detection/map_replay.h"

#include "openable/detection/frame_outcome.h"
#include "openable/detection/loop_confirmation.h"
#include "openable/detection/loop_detector.h"

namespace openable
{
std::vector<MapLoop> replayLoops(const SessionMap& map, const Config& config)
{
  // Unbounded: a session replayed must keep every frame it holds, so positions stay those of the map.
  Config replay = config;
  replay.max_history = 0;
  std::vector<MapLoop> loops;
  SessionMap grown(map.layout(), map.configYaml());
  for (uint32_t s = 0; s < map.sessionCount(); ++s)
  {
    LoopDetector detector(replay, grown, MapMode::Continue, map.session(s));
    LoopDecision decision(replay);
    LoopConfirmation confirmation(replay.confirm_frames);  // as the session's run confirmed its loops
    const PlaceDatabase& frames = map.frames(s);
    for (size_t p = 0; p < frames.size(); ++p)
    {
      const FrameDescriptor query(frames.descriptor(p), frames.descriptor(p) + frames.layout().frameWords());
      FrameOutcome outcome;
      outcome.frame = p;
      outcome.detection = detector.process(query, frames.info(p));
      outcome.status = decision.decide(outcome.detection);
      detector.setSearching(outcome.status != FrameStatus::Published || decision.keepsSearching());
      outcome.score = decision.score(outcome.detection);
      std::vector<FrameOutcome> published =
          confirmation.stored(outcome, decision.joinedBefore(), decision.mayJoinLater(), decision.ownFramesBefore());
      placeInHindsight(published, outcome);
      if (outcome.published())  // confirm_frames 0
        published.push_back(outcome);
      for (const FrameOutcome& o : published)
      {
        const Detection& d = o.detection;
        MapLoop loop;
        loop.query_session = s;
        loop.query_id = frames.firstId() + o.frame;
        loop.match_session = d.best.session;
        loop.match_id = map.frames(d.best.session).firstId() + d.best.position;
        loop.distance = d.best.distance;
        loop.score = o.score;
        loops.push_back(loop);
      }
    }
    grown = detector.map();
  }
  return loops;
}

}  // namespace openable
