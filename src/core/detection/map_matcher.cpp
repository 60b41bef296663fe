#include "openable/detection/map_matcher.h"

#include <algorithm>
#include <cmath>

#include "openable/detection/loop_decision.h"
#include "openable/error.h"
#include "openable/matching/pace_matcher.h"

namespace openable
{
bool atShortMapStart(const Candidate& best, bool short_map, uint32_t own_session, uint64_t first_id)
{
  return short_map && best.session == own_session && best.id == first_id && best.direction == 1;
}

bool onlyExcludedPast(const Detection& detection, size_t other_frames)
{
  return detection.top.empty() && detection.own_excluded && other_frames == 0;
}

MatchOptions MatchOptions::from(const Config& config)
{
  MatchOptions o;
  o.sequence_length = config.sequence_length;
  o.min_sequence_length = config.min_sequence_length;
  o.min_loop_sequence_length = config.min_loop_sequence_length;
  o.bidirectional = config.bidirectional;
  o.max_pace = config.max_pace;
  o.pace_penalty = config.pace_penalty;
  o.pace_tolerance = config.pace_tolerance;
  o.slip_penalty = config.slip_penalty;
  o.pace_prior = config.pace_prior;
  o.screen_places = config.screen_places;
  o.exclusion_window = config.exclusion_window;
  o.short_map_exclusion = config.short_map_exclusion;
  o.exclusion_seconds = config.exclusion_seconds;
  o.top_k = config.top_k;
  o.uniqueness_window = config.uniqueness_window;
  return o;
}

MapMatcher::MapMatcher(const MatchOptions& options, const DescriptorLayout& layout, bool partial_sequences)
  : options_(options), partial_sequences_(partial_sequences), metric_(layout)
{
}

MapMatcher::MapMatcher(const Config& config, const DescriptorLayout& layout, bool partial_sequences)
  : MapMatcher(MatchOptions::from(config), layout, partial_sequences)
{
}

std::unique_ptr<RowMatcher> MapMatcher::makeMatcher(const DescriptorLayout& layout) const
{
  if (options_.max_pace <= 1)
    return std::make_unique<SequenceMatcher>(layout, options_.sequence_length, options_.bidirectional);
  PaceOptions pace;
  pace.max_pace = options_.max_pace;
  pace.penalty = static_cast<float>(options_.pace_penalty);
  pace.tolerance = options_.pace_tolerance;
  pace.slip = static_cast<float>(options_.slip_penalty);
  pace.prior = static_cast<float>(options_.pace_prior);
  pace.screen_chunks = PaceMatcher::chunksOf(static_cast<size_t>(options_.screen_places));
  return std::make_unique<PaceMatcher>(layout, options_.sequence_length, options_.bidirectional, pace);
}

int MapMatcher::minTerms() const
{
  const int least = partial_sequences_ ? options_.min_sequence_length : options_.min_loop_sequence_length;
  return least == 0 ? options_.sequence_length : std::min(least, options_.sequence_length);
}

void MapMatcher::earlyPicks(std::vector<Pick>& picks, size_t wanted, size_t window)
{
  // A route walked again sooner than min_candidates places beyond the short window (40 places: the revisit's frames
  // 40-50) has no candidate at its revisit's first frames: too early, and a run could not reach back to them (their
  // best match unknown). Their best paths, however short, are that evidence: the frames stay too early (no
  // candidate is counted, so nothing is decided on them) and a consistent run joins those on its line.
  short_matcher_->smallestDistinct(wanted, window, kEarlyTerms, taken_);
  const auto session = static_cast<uint32_t>(short_session_);
  for (size_t column : taken_)
    picks.push_back({short_matcher_->normalized(column, nullptr, kEarlyTerms), session, column});
}

size_t MapMatcher::candidateColumns(const PlaceDatabase& frames, bool own, double stamp, int excluded_frames) const
{
  if (!own)
    return frames.size();
  const size_t excluded = static_cast<size_t>(std::max(0, excluded_frames));
  size_t columns = frames.size() > excluded ? frames.size() - excluded : 0;
  if (options_.exclusion_seconds > 0.0 && stamp > 0.0)
  {
    // Stamps grow along a session (the caller refuses time jumps): the first position stamped too
    // recently, by binary search.
    const double newest_allowed = stamp - options_.exclusion_seconds;
    size_t low = 0, high = columns;
    while (low < high)
    {
      const size_t middle = low + (high - low) / 2;
      if (frames.stamp(middle) > newest_allowed)
        high = middle;
      else
        low = middle + 1;
    }
    columns = low;
  }
  return columns;
}

RowMatcher* MapMatcher::shortMapMatcher(const PlaceDatabase& frames)
{
  const int64_t most = 2 * int64_t(options_.exclusion_window) + options_.sequence_length;
  const bool is_short = options_.short_map_exclusion >= 0 &&
                        options_.short_map_exclusion < options_.exclusion_window &&
                        static_cast<int64_t>(frames.size()) <= most;
  if (!is_short)
    short_matcher_.reset();
  else if (!short_matcher_)
  {
    short_matcher_ = makeMatcher(metric_.layout());
    short_matcher_->setSearching(searching_);
  }
  return short_matcher_.get();
}

const RowMatcher& MapMatcher::matcherOf(uint32_t session) const
{
  return static_cast<int>(session) == short_session_ ? *short_matcher_ : *matchers_[session];
}

Candidate MapMatcher::candidateAt(const SessionMap& map, uint32_t session, size_t column, int min_terms) const
{
  const RowMatcher& matcher = matcherOf(session);
  const PlaceDatabase& frames = map.frames(session);
  Candidate c;
  int direction = 1;
  c.distance = matcher.normalized(column, &direction, min_terms);
  c.sequence_length = matcher.terms(column, direction);
  c.pace = matcher.pace(column);
  c.direction = static_cast<int8_t>(direction);
  c.session = session;
  c.id = matcher.firstId() + column;
  c.position = static_cast<size_t>(c.id - frames.firstId());
  if (frames.layout().blocks > 1)
  {
    int shift = 0;
    metric_.distance(last_query_.data(), frames.descriptor(c.position), &shift);
    c.shift = static_cast<int16_t>(shift);
  }
  else if (!last_shifted_.empty())
    c.shift = static_cast<int16_t>(viewNearest(frames.descriptor(c.position)));
  return c;
}

int MapMatcher::viewNearest(const uint64_t* place) const
{
  // One frame's distances at the place already chosen (not the row's minimum, where every place takes its nearest
  // view): a backend told -1 or +1 knows the match faces lateral_shift of the view away from the query. A view must be
  // strictly nearer than the centre, the centre's own place, to count.
  const size_t words = last_query_.size();
  const uint32_t centre = metric_.distance(last_query_.data(), place);
  const uint32_t left = metric_.distance(last_shifted_.data(), place);
  const uint32_t right = metric_.distance(last_shifted_.data() + words, place);
  if (std::min(left, right) >= centre)
    return 0;
  return left <= right ? -1 : 1;
}

Detection MapMatcher::match(const FrameDescriptor& query, const SessionMap& map, int own_session, double stamp,
                            const FrameDescriptor& shifted)
{
  const size_t words = map.layout().frameWords();
  if (query.size() != words)
    throw Error("descriptor of " + std::to_string(query.size()) + " words does not fit the map's " +
                std::to_string(words) + " words");
  if (shifted.size() % words != 0)
    throw Error("shifted views of " + std::to_string(shifted.size()) + " words are not whole descriptors of " +
                std::to_string(words) + " words");
  last_query_ = query;
  last_shifted_ = shifted.size() == 2 * words ? shifted : FrameDescriptor();
  while (matchers_.size() < map.sessionCount())
    matchers_.push_back(makeMatcher(map.layout()));

  // Top-k distinct places: each session's own (its matcher answers from what it summarised while
  // matching: no pass over a row of N floats), then the best of them all. A uniqueness window never
  // reaches into another session, so this picks exactly what one scan of all sessions' rows would.
  Detection detection;
  const size_t wanted = static_cast<size_t>(std::max(options_.top_k, 2));
  const size_t window = static_cast<size_t>(std::max(0, options_.uniqueness_window));
  std::vector<Pick>& picks = picks_;  // reused: no allocation per frame
  picks.clear();
  short_session_ = -1;
  for (uint32_t s = 0; s < map.sessionCount(); ++s)
  {
    const bool own = static_cast<int>(s) == own_session;
    const PlaceDatabase& frames = map.frames(s);
    size_t columns = candidateColumns(frames, own, stamp, options_.exclusion_window);
    RowMatcher* matcher = matchers_[s].get();
    RowMatcher* short_map = own ? shortMapMatcher(frames) : nullptr;
    if (short_map)
    {
      // The session's own matcher goes on as without the short window (its state is what a longer map builds on);
      // the short map's matcher answers for the session.
      matcher->matchShifted(query.data(), shifted.data(), shifted.size() / words, frames, columns);
      columns = candidateColumns(frames, own, stamp, options_.short_map_exclusion);
      matcher = short_map;
      detection.short_map = true;
      short_session_ = own_session;
    }
    detection.own_excluded = detection.own_excluded || (own && columns == 0 && !frames.empty());
    if (own && columns > 0 && columns < frames.size())
    {
      detection.has_exclusion_edge = true;
      detection.exclusion_edge_session = s;
      detection.exclusion_edge_id = frames.firstId() + columns - 1;
    }
    matcher->matchShifted(query.data(), shifted.data(), shifted.size() / words, frames, columns);
    detection.candidates += matcher->smallestDistinct(wanted, window, minTerms(), taken_);
    for (size_t column : taken_)
      picks.push_back({matcher->normalized(column, nullptr, minTerms()), s, column});
  }
  const bool early = detection.candidates == 0 && short_session_ >= 0;
  if (early)
    earlyPicks(picks, wanted, window);
  const int terms = early ? kEarlyTerms : minTerms();
  // By distance; ties to the earlier session, then the lower column (as one scan would).
  std::stable_sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) { return a.distance < b.distance; });
  if (picks.size() > wanted)
    picks.resize(wanted);
  for (size_t i = 0; i < picks.size() && i < static_cast<size_t>(options_.top_k); ++i)
  {
    // Each path's end placed between the paces followed (its distance and pace stay the path's): each candidate is
    // its own session's, so place servers that split the sessions report what one server would.
    Candidate c = candidateAt(map, picks[i].session, picks[i].column, terms);
    const size_t refined = matcherOf(picks[i].session).refinedColumn(picks[i].column);
    if (refined != picks[i].column)
    {
      const Candidate path = c;
      c = candidateAt(map, picks[i].session, refined, terms);
      c.distance = path.distance;
      c.pace = path.pace;
    }
    detection.top.push_back(c);
  }

  // No candidate although the stream's own past exists and nothing else is in the map: the exclusion.
  const size_t other_frames = detection.own_excluded
                                  ? map.frameCount() - map.frames(static_cast<uint32_t>(own_session)).size()
                                  : map.frameCount();
  detection.excluded = onlyExcludedPast(detection, other_frames);
  if (!detection.top.empty())
  {
    detection.has_candidates = true;
    detection.best = detection.top.front();
    detection.uniqueness = matchUniqueness(detection.best.distance,
                                           picks.size() < 2 ? std::nullopt : std::optional<float>(picks[1].distance));
    detection.relief = reliefAround(map, detection.best);
    if (detection.short_map)
      detection.best_at_session_start = atShortMapStart(detection.best, true, static_cast<uint32_t>(own_session),
                                                        map.frames(static_cast<uint32_t>(own_session)).firstId());
  }
  return detection;
}

float MapMatcher::reliefAround(const SessionMap& map, const Candidate& best) const
{
  // The query's own distances to the places around its match (2 x uniqueness_window + 1 frame distances, next
  // to the pass over the row): a sequence localises by how these differ, and where they do not (Nordland's
  // snowfields, every place within 10 of the match as far from the query as its match), a path drifts along
  // the stretch unnoticed: all of the 12 wrong loops of Nordland summer then winter at 1x (doc/results.md).
  const RowMatcher& matcher = matcherOf(best.session);
  const float spread = matcher.rowSpread();
  if (!std::isfinite(spread))
    return std::nanf("");
  const PlaceDatabase& frames = map.frames(best.session);
  const uint64_t window = static_cast<uint64_t>(std::max(0, options_.uniqueness_window));
  const uint64_t first = std::max({frames.firstId(), matcher.firstId(), best.id > window ? best.id - window : 0});
  const uint64_t last = std::min(best.id + window, matcher.firstId() + matcher.columns() - 1);
  double lowest = 1.0, highest = 0.0;
  for (uint64_t id = first; id <= last && id - frames.firstId() < frames.size(); ++id)
  {
    const uint64_t* place = frames.descriptor(static_cast<size_t>(id - frames.firstId()));
    const double d = metric_.normalizedDistance(last_query_.data(), place);
    lowest = std::min(lowest, d);
    highest = std::max(highest, d);
  }
  if (highest < lowest)
    return std::nanf("");
  return spread > 0.0f ? static_cast<float>((highest - lowest) / spread) : 0.0f;
}

void MapMatcher::lastRow(const SessionMap& map, std::vector<float>& out) const
{
  out.clear();
  for (uint32_t s = 0; s < map.sessionCount(); ++s)
  {
    const PlaceDatabase& frames = map.frames(s);
    const size_t start = out.size();
    out.resize(start + frames.size(), std::nanf(""));
    if (s >= matchers_.size())
      continue;
    const RowMatcher& matcher = matcherOf(s);
    for (size_t c = 0; c < matcher.columns(); ++c)
    {
      const uint64_t id = matcher.firstId() + c;
      if (id < frames.firstId())
        continue;  // evicted after matching
      const size_t position = static_cast<size_t>(id - frames.firstId());
      if (position < frames.size())
        out[start + position] = matcher.normalized(c, nullptr, minTerms());
    }
  }
}

void MapMatcher::setOptions(const MatchOptions& options)
{
  const bool new_kind = (options.max_pace <= 1) != (options_.max_pace <= 1) || options.max_pace != options_.max_pace ||
                        options.pace_penalty != options_.pace_penalty ||
                        options.pace_tolerance != options_.pace_tolerance ||
                        options.slip_penalty != options_.slip_penalty || options.pace_prior != options_.pace_prior ||
                        options.screen_places != options_.screen_places;
  if (new_kind || options.short_map_exclusion != options_.short_map_exclusion)
  {
    short_matcher_.reset();  // the next short map's frame makes it afresh
    short_session_ = -1;
  }
  if (new_kind)
  {
    options_ = options;
    for (auto& matcher : matchers_)
      matcher = makeMatcher(metric_.layout());
    return;
  }
  if (short_matcher_)
  {
    if (options.sequence_length != options_.sequence_length)
      short_matcher_->setSequenceLength(options.sequence_length);
    if (options.bidirectional != options_.bidirectional)
      short_matcher_->setBidirectional(options.bidirectional);
  }
  for (auto& matcher : matchers_)
  {
    if (options.sequence_length != options_.sequence_length)
      matcher->setSequenceLength(options.sequence_length);
    if (options.bidirectional != options_.bidirectional)
      matcher->setBidirectional(options.bidirectional);
  }
  options_ = options;
}

void MapMatcher::setSearching(bool searching)
{
  searching_ = searching;
  for (auto& matcher : matchers_)
    matcher->setSearching(searching);
  if (short_matcher_)
    short_matcher_->setSearching(searching);
}

void MapMatcher::reset()
{
  for (auto& matcher : matchers_)
    matcher->reset();
  if (short_matcher_)
    short_matcher_->reset();
}

}  // namespace openable
