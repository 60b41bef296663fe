#include "openable/detection/online_detector.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "openable/error.h"
#include "openable/description/input_contract.h"
#include "openable/description/stereo.h"

namespace openable
{
namespace
{
void checkOptions(const OnlineOptions& options)
{
  if (!std::isfinite(options.keyframe_distance) || options.keyframe_distance < 0.0)
    throw Error("keyframe_distance: value " + std::to_string(options.keyframe_distance) +
                " is not allowed; expected metres >= 0 (0 = every frame)");
  if (!std::isfinite(options.keyframe_angle) || options.keyframe_angle < 0.0)
    throw Error("keyframe_angle: value " + std::to_string(options.keyframe_angle) +
                " is not allowed; expected radians >= 0 (0 = off)");
}

/// How far a frame got through a channel's decision: a loop closure (published or pending), one that
/// verification stopped, one of a run's first frames, or none.
int decisionProgress(FrameStatus status)
{
  switch (status)
  {
    case FrameStatus::Published:
    case FrameStatus::Pending:
      return 3;
    case FrameStatus::Unverified:
    case FrameStatus::FailedVerification:
      return 2;
    case FrameStatus::Inconsistent:
      return 1;
    default:
      return 0;
  }
}

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

PlaceDatabase nonEmpty(PlaceDatabase map)
{
  if (map.empty())
    throw Error("the reference map holds no frame; expected a map with at least one place");
  return map;
}

SessionMap nonEmptyWhenLocalising(SessionMap map, MapMode mode)
{
  if (mode == MapMode::Localise && map.frameCount() == 0)
    throw Error("the reference map holds no frame; expected a map with at least one place");
  return map;
}

/// Angle (radians) between two orientations given as quaternions (x y z w at indices 3..6).
double rotationBetween(const std::array<double, 7>& a, const std::array<double, 7>& b)
{
  double dot = 0.0, na = 0.0, nb = 0.0;
  for (int i = 3; i < 7; ++i)
  {
    dot += a[i] * b[i];
    na += a[i] * a[i];
    nb += b[i] * b[i];
  }
  if (na <= 0.0 || nb <= 0.0)
    return 0.0;
  const double c = std::min(1.0, std::fabs(dot) / std::sqrt(na * nb));
  return 2.0 * std::acos(c);
}
}  // namespace

// The configuration is validated once, here (ValidConfig); the describer and the detector take it as valid.
OnlineDetector::OnlineDetector(const Config& config, const OnlineOptions& options)
  : OnlineDetector(ValidConfig(config), options)
{
}

OnlineDetector::OnlineDetector(const ValidConfig& config, const OnlineOptions& options)
  : config_(*config),
    options_(options),
    describer_(config),
    detector_(config),
    decision_(*config),
    confirmation_(config->confirm_frames),
    metric_(describer_.layout()),
    features_(options.feature_bytes)
{
  checkOptions(options);
  startViewChannel();
}

OnlineDetector::OnlineDetector(const Config& config, PlaceDatabase reference_map, const OnlineOptions& options)
  : OnlineDetector(ValidConfig(config), std::move(reference_map), options)
{
}

OnlineDetector::OnlineDetector(const ValidConfig& config, PlaceDatabase reference_map, const OnlineOptions& options)
  : config_(*config),
    options_(options),
    describer_(config),
    detector_(config, nonEmpty(std::move(reference_map))),
    decision_(*config),
    confirmation_(config->confirm_frames),
    metric_(describer_.layout()),
    features_(options.feature_bytes)
{
  checkOptions(options);
}

OnlineDetector::OnlineDetector(const Config& config, SessionMap map, MapMode mode, SessionInfo session,
                               const OnlineOptions& options)
  : OnlineDetector(ValidConfig(config), std::move(map), mode, std::move(session), options)
{
}

OnlineDetector::OnlineDetector(const ValidConfig& config, SessionMap map, MapMode mode, SessionInfo session,
                               const OnlineOptions& options)
  : config_(*config),
    options_(options),
    describer_(config),
    detector_(config, nonEmptyWhenLocalising(std::move(map), mode), mode, std::move(session)),
    decision_(*config),
    confirmation_(config->confirm_frames),
    metric_(describer_.layout()),
    features_(options.feature_bytes)
{
  checkOptions(options);
  // A map's earlier sessions hold the whole image's places alone: the view channel has nothing to match there.
  if (mode == MapMode::Continue && detector_.map().frameCount() == 0)
    startViewChannel();
}

void OnlineDetector::startViewChannel()
{
  // Only where the whole image has no views of its own (lateral_shift), and where views can be cut: not from a ring
  // (matched at every rotation already) nor from disparity (it does not shift with the image).
  if (config_.view_channel_shift <= 0.0 || config_.lateral_shift > 0.0 ||
      config_.camera() == CameraType::Panoramic || describer_.descriptor().needs_disparity)
    return;
  const SessionInfo& session = detector_.map().session(static_cast<uint32_t>(detector_.ownSession()));
  views_ = std::make_unique<ViewChannel>(ValidConfig(config_.viewChannel()), session);
  views_on_ = true;
}

std::vector<Patch> OnlineDetector::patches(const FrameInput& input) const
{
  const Preprocessor& pre = describer_.preprocessor();
  // Camera and descriptor were parsed once, when the describer was built: nothing is looked up per frame.
  if (pre.options().camera == CameraType::Panoramic && !input.cameras.empty())
  {
    for (size_t i = 0; i < input.cameras.size(); ++i)
    {
      const InputProblem size = checkImageSize(input.cameras[i].cols, input.cameras[i].rows);
      if (!size.ok() && !input.cameras[i].empty())
        throw FrameRefused(size.reason, "camera " + std::to_string(i) + " of the ring: " + size.what);
    }
    return pre.patchesFromCameras(input.cameras);
  }
  if (input.image.empty())
    throw Error("empty image; expected an 8-bit grey, BGR or BGRA image");
  const InputProblem size = checkImageSize(input.image.cols, input.image.rows);
  if (!size.ok())
    throw FrameRefused(size.reason, size.what);
  if (!describer_.descriptor().needs_disparity)
    return pre.patches(input.image);  // stereo with a mono descriptor: the left image only, no SGBM cost
  if (!input.disparity.empty())
    return pre.patchesWithDisparity(input.image, disparityFromImage(input.disparity));
  if (input.right.empty())
    throw Error("descriptor " + config_.descriptor + " needs the right image or a disparity image besides the left one");
  return pre.patchesWithDisparity(input.image, disparityFromPair(input.image, input.right, config_));
}

std::vector<Patch> OnlineDetector::placePatches(const FrameInput& input) const
{
  std::vector<Patch> cells = patches(input);
  const InputProblem texture = checkTexture(cells, config_.illumination_invariance);
  if (!texture.ok())
    throw FrameRefused(texture.reason, texture.what);
  return cells;
}

FrameDescriptor OnlineDetector::describe(const FrameInput& input) const
{
  return describer_.describe(placePatches(input));
}

FrameDescriptor OnlineDetector::shiftedViews(const FrameDescriber& describer, const FrameInput& input) const
{
  const Preprocessor& pre = describer.preprocessor();
  FrameDescriptor views;
  if (input.image.empty() || !pre.hasShiftedViews(input.image.size()) || describer.descriptor().needs_disparity)
    return views;
  // The place stores its centre; the frame looks for it from both sides too (a camera on the other side of the
  // path, or turned a little, sees the scene shifted by a tenth of the image or more).
  const size_t words = describer.layout().frameWords();
  views.resize(2 * words);
  describer.describe(pre.patches(input.image, Preprocessor::View::Left), views.data());
  describer.describe(pre.patches(input.image, Preprocessor::View::Right), views.data() + words);
  return views;
}

FrameOutcome OnlineDetector::matchViews(const FrameInput& input, const FrameOutcome& stored)
{
  FrameOutcome viewed;
  viewed.view_channel = true;
  viewed.query = stored.query;
  viewed.stored = true;
  viewed.frame = frames_;
  // The whole image was described already: the image is good. Its centre crop is the channel's place.
  const FrameDescriptor centre = views_->describer.describe(views_->describer.preprocessor().patches(input.image));
  viewed.detection = views_->detector.process(centre, stored.query, shiftedViews(views_->describer, input));
  lookUpMatch(viewed);  // the same frames, stored in both channels: one id names a frame in either
  return viewed;
}

bool OnlineDetector::isKeyframe(const FrameInput& input)
{
  if (options_.keyframe_distance <= 0.0 && options_.keyframe_angle <= 0.0)
    return true;
  // Without a pose the motion is unknown: keeping the frame loses nothing, skipping it could.
  if (!input.has_pose)
    return true;
  if (!has_keyframe_pose_)
  {
    has_keyframe_pose_ = true;
    keyframe_pose_ = input.pose;
    return true;
  }
  const double dx = input.pose[0] - keyframe_pose_[0];
  const double dy = input.pose[1] - keyframe_pose_[1];
  const double dz = input.pose[2] - keyframe_pose_[2];
  const bool moved =
      (options_.keyframe_distance > 0.0 && std::sqrt(dx * dx + dy * dy + dz * dz) >= options_.keyframe_distance) ||
      (options_.keyframe_angle > 0.0 && rotationBetween(keyframe_pose_, input.pose) >= options_.keyframe_angle);
  if (moved)
    keyframe_pose_ = input.pose;
  return moved;
}

OnlineDetector::Stillness OnlineDetector::stillness(const FrameDescriptor& descriptor,
                                                    const std::vector<Patch>& cells) const
{
  if (!has_last_stored_ || last_stored_.size() != descriptor.size())
    return Stillness::Moving;
  // The same image again (standstill_distance), or a real camera's noise: standing still, it never gives the same
  // image twice. EuRoC V1_01's first 40 frames (the MAV on the ground, 20 Hz) lie 0.006 apart (2 bits of HOG-B's
  // 324) and all within 0.031 of the first, while no two consecutive frames of a moving camera here come closer
  // than 0.043 (KITTI 07 at 10 Hz) or 0.049 (Gardens Point). The noise is judged against the still stretch's
  // first frame too, so a noisy frame that strays from the last stored one does not start a new stretch.
  const double to_last = metric_.normalizedDistance(descriptor.data(), last_stored_.data());
  const bool repeated = config_.standstill_distance > 0.0 && to_last <= config_.standstill_distance;
  const auto withinNoise = [&](const FrameDescriptor& still)
  {
    return still.size() == descriptor.size() &&
           metric_.normalizedDistance(descriptor.data(), still.data()) <= config_.stop_distance;
  };
  const bool noise =
      config_.stop_distance > 0.0 && (to_last <= config_.stop_distance || withinNoise(still_anchor_));
  // A black tunnel frame is the same descriptor at any speed (kMinTextureStdDev): it says nothing about motion.
  // The illumination-invariant image has another scale: not tested there.
  if (!(repeated || noise) || !(config_.illumination_invariance || textured(cells, kMinTextureStdDev)))
    return Stillness::Moving;
  return repeated ? Stillness::Repeated : Stillness::WithinNoise;
}

FrameOutcome OnlineDetector::process(const FrameInput& original)
{
  FrameOutcome outcome = processFrame(original);
  outcome.frame = frames_++;
  if (views_)
  {
    reported_.push_back({outcome.status, outcome.view_channel, outcome.published()});
    if (reported_.size() > kJoinFrames)
      reported_.pop_front();
  }
  return outcome;
}

FrameOutcome OnlineDetector::processFrame(const FrameInput& original)
{
  // The input contract (input_contract.h): bad stamps and poses are refused before anything changes.
  const InputProblem stamp = checkStamp(original.stamp, last_stamp_, last_stamp_ > 0.0, options_.require_stamps);
  if (stamp.reason == "stamp went backwards")
  {
    FrameOutcome jumped;
    jumped.query.stamp = original.stamp;
    jumped.query.session = original.session;
    jumped.query.source = original.source;
    jumped.status = FrameStatus::TimeJump;
    return jumped;
  }
  if (!stamp.ok())
    throw FrameRefused(stamp.reason, stamp.what);
  FrameInput input_copy;
  const FrameInput* checked = &original;
  if (original.has_pose)
  {
    Pose pose = original.pose;
    const InputProblem problem = checkPose(pose);
    if (!problem.ok())
      throw FrameRefused(problem.reason, problem.what);
    if (pose != original.pose)
    {
      input_copy = original;  // cv::Mat copies share their pixels
      input_copy.pose = pose;
      checked = &input_copy;
    }
  }
  const FrameInput& input = *checked;
  FrameOutcome outcome;
  outcome.query.stamp = input.stamp;
  outcome.query.session = input.session;
  outcome.query.source = input.source;
  outcome.query.has_pose = input.has_pose;
  outcome.query.pose = input.pose;
  if (!isKeyframe(input))
  {
    outcome.status = FrameStatus::NotKeyframe;
    return outcome;
  }
  // Bad input throws here, before anything is stored.
  auto start = std::chrono::steady_clock::now();
  const std::vector<Patch> cells = placePatches(input);
  outcome.times.preprocess_ms = millisecondsSince(start);
  start = std::chrono::steady_clock::now();
  const FrameDescriptor descriptor = describer_.describe(cells);
  outcome.times.describe_ms = millisecondsSince(start);
  if (input.stamp > 0.0)
    last_stamp_ = input.stamp;
  const Stillness still = stillness(descriptor, cells);
  if (still == Stillness::Repeated)
  {
    // The same place as the last stored frame: it adds no place and no step to the sequences (a stop must
    // neither grow the history nor become a "revisit" of itself), and it repeats that frame's loop closure.
    const auto repeat = [&](FrameOutcome repeated)
    {
      repeated.stored = false;
      repeated.query.stamp = input.stamp;
      repeated.query.source = input.source;
      repeated.query.has_pose = input.has_pose;
      repeated.query.pose = input.pose;
      repeated.times = outcome.times;
      repeated.frame = frames_;
      if (!repeated.published() && repeated.status != FrameStatus::Pending)
        repeated.status = FrameStatus::Standstill;
      return repeated;
    };
    // A pending loop closure's repeats wait with it, in each channel.
    confirmation_.repeated(repeat(last_whole_outcome_));
    if (views_on_)
      views_->confirmation.repeated(repeat(last_view_outcome_));
    return repeat(last_outcome_);
  }
  const bool still_noise = still == Stillness::WithinNoise;
  if (config_.stop_distance > 0.0 && still_frames_ >= config_.stop_frames)
  {
    // A camera that has stayed within its own noise for stop_frames stored frames has stopped (a red light, a
    // robot waiting): the frame adds no place and no step to the sequences. The stop ends with the second frame
    // in a row out of that noise (one strays now and then: EuRoC's frame 15, 10 bits off the first). Unlike an
    // exact repeat it repeats no loop closure: a camera creeping through a featureless stretch (Nordland's
    // snowfields, frames 10 s apart within 0.02 of each other) looks the same, and the loop would be places off.
    frames_out_of_noise_ = still_noise ? 0 : frames_out_of_noise_ + 1;
    if (frames_out_of_noise_ < kFramesThatEndAStop)
    {
      outcome.status = FrameStatus::Standstill;
      return outcome;
    }
  }

  start = std::chrono::steady_clock::now();
  const FrameDescriptor shifted = shiftedViews(describer_, input);
  outcome.times.describe_ms += millisecondsSince(start);
  start = std::chrono::steady_clock::now();
  outcome.detection = detector_.process(descriptor, outcome.query, shifted);
  outcome.stored = true;
  outcome.query.id = outcome.detection.query_id;
  if (!detector_.localisationMode())
    outcome.query.session = static_cast<uint32_t>(detector_.ownSession());
  lookUpMatch(outcome);
  outcome.frame = frames_;
  // The view channel stores every frame the whole image's does, so that both number them alike; a stream whose
  // images are too small for views never has any (a Nordland frame of 64x32): the channel would only repeat the
  // whole image on fewer bits.
  if (views_on_ && !views_->describer.preprocessor().hasShiftedViews(input.image.size()))
    views_on_ = false;
  FrameOutcome viewed;
  if (views_on_)
    viewed = matchViews(input, outcome);
  outcome.times.match_ms = millisecondsSince(start);
  start = std::chrono::steady_clock::now();
  std::unique_ptr<FrameFeatures> query = queryFeatures(input, outcome);
  std::vector<FrameOutcome> confirmed = decideAndConfirm({detector_, decision_, confirmation_}, query.get(), outcome);
  last_whole_outcome_ = outcome;
  if (views_on_)
  {
    std::vector<FrameOutcome> view_confirmed =
        decideAndConfirm({views_->detector, views_->decision, views_->confirmation}, query.get(), viewed);
    last_view_outcome_ = viewed;
    confirmed = joinChannels(outcome, std::move(confirmed), viewed, std::move(view_confirmed));
  }
  if (query && !detector_.localisationMode())
    features_.insert(std::move(*query));  // every stored frame keeps its features: later frames may close a loop with it
  outcome.times.verify_ms = millisecondsSince(start);
  has_last_stored_ = true;
  last_stored_ = descriptor;
  last_outcome_ = outcome;
  if (still_noise)
    ++still_frames_;
  else
  {
    still_frames_ = 0;
    frames_out_of_noise_ = 0;
    still_anchor_ = descriptor;
  }
  outcome.confirmed = std::move(confirmed);
  return outcome;
}

std::vector<FrameOutcome> OnlineDetector::decideAndConfirm(Channel channel, const FrameFeatures* query,
                                                           FrameOutcome& outcome)
{
  // Verification runs at most once a frame: where the decision asks for it (a frame that lacks appearance
  // evidence), or on what it published.
  bool asked = false;
  const auto verifyOnce = [&]
  {
    if (!asked)
      verifyBestMatch(query, outcome);
    asked = true;
    return outcome.verified;
  };
  LoopDecision& decision = channel.decision;
  outcome.status = decision.decide(outcome.detection,
                                   options_.verify ? LoopDecision::GeometryCheck(verifyOnce) : nullptr);
  outcome.score = decision.score(outcome.detection);
  // The matcher follows the decision's run (what verification does with it comes after): a stream whose loops are
  // only flagged unverified matches as one whose loops are published.
  channel.detector.setSearching(outcome.status != FrameStatus::Published || decision.keepsSearching());
  // A run's first frames (Inconsistent) may join its loop closure later (run_start_tolerance): they are checked
  // as a published frame is, and one that verification rejects breaks the chain of frames that may join.
  const bool run_start = outcome.status == FrameStatus::Inconsistent && decision.mayJoinLater();
  if (options_.verify && (outcome.published() || run_start))
  {
    verifyOnce();
    if (!outcome.verification_ran && options_.verify_required)  // nothing through that it could not check
      outcome.status = FrameStatus::Unverified;
    else if (outcome.verification_ran && !outcome.verified && config_.verification_veto)
      outcome.status = FrameStatus::FailedVerification;
  }
  // A frame that may join a later run: as the decision says, unless verification must accept every loop closure
  // and did not check it (not-unique frames are not verified: that would be every frame, nor a short map's too early
  // ones, nor the featureless ones a published run coasts through, which the decision lets join).
  const bool strict = options_.verify && (config_.verification_veto || options_.verify_required);
  const bool unchecked = outcome.status == FrameStatus::NotUnique || outcome.status == FrameStatus::TooEarly ||
                         outcome.status == FrameStatus::Featureless;
  const bool may_join =
      decision.mayJoinLater() && (outcome.status == FrameStatus::Inconsistent || (unchecked && !strict));
  std::vector<FrameOutcome> confirmed =
      channel.confirmation.stored(outcome, decision.joinedBefore(), may_join, decision.ownFramesBefore());
  placeInHindsight(confirmed, outcome);
  for (FrameOutcome& c : confirmed)
    if (!c.has_match_info)
      lookUpMatch(c);
  return confirmed;
}

std::vector<FrameOutcome> OnlineDetector::joinChannels(FrameOutcome& outcome, std::vector<FrameOutcome> confirmed,
                                                       const FrameOutcome& viewed,
                                                       std::vector<FrameOutcome> view_confirmed)
{
  // A frame's first loop closure goes out; it moves its frame from the status the frame was reported with when
  // that was the other channel's decision. A later one of the same frame is dropped.
  const auto first = [this](FrameOutcome& c)
  {
    Reported* reported = c.frame < frames_ && frames_ - c.frame <= reported_.size()
                             ? &reported_[reported_.size() - (frames_ - c.frame)]
                             : nullptr;
    if (!reported)
      return true;
    if (reported->published)
      return false;
    reported->published = true;
    if (reported->view_channel != c.view_channel)
      c.status_before = reported->status;
    return true;
  };
  std::vector<FrameOutcome> joined;
  for (std::vector<FrameOutcome>* channel : {&confirmed, &view_confirmed})
    for (FrameOutcome& c : *channel)
      if (first(c))
        joined.push_back(std::move(c));
  std::stable_sort(joined.begin(), joined.end(),
                   [](const FrameOutcome& a, const FrameOutcome& b) { return a.frame < b.frame; });
  // This frame's own decision: the whole image's, unless the view channel took it further (published or pending,
  // then stopped by verification, then a run's first frame), so that its status says what the frame got to.
  if (decisionProgress(viewed.status) > decisionProgress(outcome.status))
  {
    const StageTimes times = outcome.times;
    outcome = viewed;
    outcome.times = times;
  }
  return joined;
}

void OnlineDetector::lookUpMatch(FrameOutcome& outcome) const
{
  if (!outcome.detection.has_candidates)
    return;
  const PlaceDatabase& frames = detector_.map().frames(outcome.detection.best.session);
  const uint64_t id = outcome.detection.best.id;
  outcome.has_match_info = id >= frames.firstId() && id - frames.firstId() < frames.size();
  if (outcome.has_match_info)
    outcome.match = frames.info(static_cast<size_t>(id - frames.firstId()));
}

std::unique_ptr<FrameFeatures> OnlineDetector::queryFeatures(const FrameInput& input, FrameOutcome& outcome) const
{
  if (!options_.verify || !verifier_ || input.image.empty())
    return nullptr;
  try
  {
    const cv::Mat right = verifier_->camera().stereo() ? input.right : cv::Mat();
    return std::make_unique<FrameFeatures>(verifier_->extract(input.image, right, outcome.query.id));
  }
  catch (const Error& e)
  {
    outcome.verification_note = std::string("no features: ") + e.what();
  }
  catch (const cv::Exception& e)
  {
    outcome.verification_note = std::string("no features (OpenCV): ") + e.what();
  }
  return nullptr;
}

void OnlineDetector::verifyBestMatch(const FrameFeatures* query, FrameOutcome& outcome) const
{
  const FrameFeatures* match = features_.find(outcome.detection.best.id);
  if (!verifier_)
    outcome.verification_note = "no camera yet";
  else if (!query)
  {
    if (outcome.verification_note.empty())  // else it already says why extraction failed
      outcome.verification_note = "no query features";
  }
  else if (!match)
    outcome.verification_note = "match frame has no features (it came before the camera, or was evicted)";
  else
  {
    outcome.verification = verifier_->verify(*match, *query);
    outcome.verification_ran = true;
    outcome.verified = outcome.verification.accepted();
    outcome.verification_note =
        outcome.verified ? ""
                         : std::string(toString(outcome.verification.status)) +
                               (outcome.verification.reason.empty() ? "" : " (" + outcome.verification.reason + ")");
  }
}

bool OnlineDetector::setCamera(const PinholeCamera& camera)
{
  if (verifier_)
  {
    const PinholeCamera& c = verifier_->camera();
    return c.fx == camera.fx && c.fy == camera.fy && c.cx == camera.cx && c.cy == camera.cy &&
           c.baseline == camera.baseline && c.image_size == camera.image_size;
  }
  verifier_ = std::make_unique<GeometricVerifier>(camera, verifierParams(config_));
  return true;
}

void OnlineDetector::updateConfig(const Config& config)
{
  // The verifier keeps the verify_* values it was built with; accepting others would make config() lie.
  std::string changed;
  for (const auto& key : Config::keys())
    if (key.name.rfind("verify_", 0) == 0 && config.get(key.name) != config_.get(key.name))
      changed += (changed.empty() ? "" : ", ") + key.name;
  if (!changed.empty())
    throw Error("cannot change " + changed + " while running: the verifier is built once; restart the detector");
  // The view channel's places are described as it was started (a map holds the whole image's alone: those keys
  // do not make maps incompatible, but a running channel cannot change them).
  for (const char* key : {"view_channel_shift", "view_channel_bits"})
    if (config.get(key) != config_.get(key))
      changed += (changed.empty() ? "" : ", ") + std::string(key);
  if (!changed.empty())
    throw Error("cannot change " + changed + " while running: the view channel's places are described with them; "
                "restart the detector");
  detector_.updateMatching(config);  // validates and refuses descriptor keys
  decision_.setOptions(DecisionOptions::from(config));
  confirmation_.setFrames(config.confirm_frames);
  if (views_)
  {
    const Config views = config.viewChannel();
    views_->detector.updateMatching(views);
    views_->decision.setOptions(DecisionOptions::from(views));
    views_->confirmation.setFrames(views.confirm_frames);
  }
  config_ = config;
}

void OnlineDetector::reset()
{
  detector_.reset();
  decision_.reset();
  confirmation_.reset();
  features_.clear();
  last_stamp_ = 0.0;
  has_keyframe_pose_ = false;
  has_last_stored_ = false;
  still_frames_ = 0;
  frames_out_of_noise_ = 0;
  still_anchor_.clear();
  reported_.clear();
  if (views_)
  {
    views_->detector.reset();
    views_->decision.reset();
    views_->confirmation.reset();
    views_on_ = true;
  }
}

}  // namespace openable
