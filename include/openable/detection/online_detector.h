#pragma once

#include <array>
#include <deque>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/matching/frame_metric.h"
#include "openable/geo_position.h"
#include "openable/verification/geometric_verifier.h"
#include "openable/detection/frame_outcome.h"
#include "openable/detection/loop_confirmation.h"
#include "openable/detection/loop_decision.h"
#include "openable/detection/loop_detector.h"

namespace openable
{
/// One synchronised input set, already converted from messages or files. Which images are used depends on
/// camera_type and descriptor (see OnlineDetector::describe).
struct FrameInput
{
  cv::Mat image;                 ///< mono image, left rectified image (stereo) or panorama
  cv::Mat right;                 ///< stereo: right rectified image (D-LDB computes the disparity with SGBM)
  cv::Mat disparity;             ///< stereo: a disparity image instead of `right` (stereo_msgs: 32FC1, < 0 invalid)
  std::vector<cv::Mat> cameras;  ///< panoramic ring: one image per camera, in ring order (instead of `image`)
  double stamp = 0.0;            ///< seconds; 0 = unknown (no time checks, no exclusion_seconds)
  uint32_t session = 0;  ///< localising: the session reported for the query (stored frames take their map session)
  std::string source;  ///< file name or topic: stored with the frame, used in messages
  bool has_pose = false;
  std::array<double, 7> pose{{0, 0, 0, 0, 0, 0, 1}};  ///< x y z qx qy qz qw in a fixed frame
  /// Where the frame was taken (e.g. the detector nodelets' ~fix). The pipeline does not use it and the map
  /// does not store it: the caller keeps it by the outcome's frame id (geoPositionsCsvLine), for the KML
  /// export (openable_trajectory --geo).
  bool has_geo = false;
  GeoPosition geo;
};

/// What the pipeline does besides the configuration's keys (the nodelets' ROS parameters map onto it).
struct OnlineOptions
{
  double keyframe_distance = 0.0;  ///< metres the camera must move before a frame is stored (0 = every frame)
  double keyframe_angle = 0.0;     ///< radians the camera must turn before a frame is stored (0 = off)
  bool verify = false;             ///< geometric verification of candidates (needs setCamera())
  bool verify_required = true;     ///< true: a candidate that cannot be verified is not published (Unverified)
                                   ///< (the verifier's tunables are the configuration's verify_* keys)
  size_t feature_bytes = 256u << 20;  ///< memory bound of the features kept for verification
  /// Every frame must carry a stamp (the nodelets: a ROS header stamp of 0 is unset). Without it a stream
  /// whose first frame is stamped 0 has no stamps (a folder of images); stamped streams refuse 0 anyway.
  bool require_stamps = false;
};

/// The view channel (Config::view_channel_shift): the image's centre crop described and matched with the frame's
/// views shifted sideways, over the same stored frames as the whole image, with its own sequences, decision and
/// confirmation. OnlineDetector joins its loop closures with the whole image's.
struct ViewChannel
{
  /// A new stream's channel, in session `session` as the whole image's (its places are numbered alike).
  ViewChannel(const ValidConfig& config, SessionInfo session)
    : describer(config), detector(config, std::move(session)), decision(*config), confirmation(config->confirm_frames)
  {
  }
  FrameDescriber describer;
  LoopDetector detector;
  LoopDecision decision;
  LoopConfirmation confirmation;
};

/// The one online pipeline: describe -> keyframe -> match -> decide -> verify. The nodelets and
/// openable_offline both call it, so the offline tool lists exactly what a nodelet publishes.
///
/// Loop-closure mode (first constructor) matches every frame against the stream's own past and stores it;
/// localisation mode matches against a fixed reference map. Not thread-safe: callers serialise.
///
/// With view_channel_shift (loop-closure mode of a new stream: the first constructor, or an empty map continued) a
/// second channel (ViewChannel) matches the same stored frames from their centre crops and shifted views; a frame's
/// loop closure is the first either channel publishes, the whole image's where both publish it at once. A stream
/// whose images are too small for views (Preprocessor::hasShiftedViews) switches the channel off until reset().
class OnlineDetector
{
public:
  /// Throws Error when the configuration or options are invalid.
  explicit OnlineDetector(const Config& config, const OnlineOptions& options = OnlineOptions());
  /// Localisation against a saved or built map. Throws Error when the map is empty or built with another
  /// descriptor configuration.
  OnlineDetector(const Config& config, PlaceDatabase reference_map, const OnlineOptions& options = OnlineOptions());
  /// A saved map of one or more sessions, localised against (MapMode::Localise) or continued as the new
  /// session `session` (MapMode::Continue: loops within the new session and with every earlier one).
  /// Throws Error when the map is empty (localising), was built with another layout, or already holds a
  /// session of that name.
  OnlineDetector(const Config& config, SessionMap map, MapMode mode, SessionInfo session,
                 const OnlineOptions& options = OnlineOptions());
  /// The same three, from a configuration validated already: the one validation of a start.
  explicit OnlineDetector(const ValidConfig& config, const OnlineOptions& options = OnlineOptions());
  OnlineDetector(const ValidConfig& config, PlaceDatabase reference_map, const OnlineOptions& options = OnlineOptions());
  OnlineDetector(const ValidConfig& config, SessionMap map, MapMode mode, SessionInfo session,
                 const OnlineOptions& options = OnlineOptions());

  /// Describes, stores, matches and decides. Bad images throw Error / cv::Exception before anything is
  /// stored, so a caller can report and carry on; what the input contract refuses (input_contract.h: a
  /// non-finite, negative or 0 stamp in a stamped stream, a non-finite pose or non-unit quaternion, an image
  /// below kMinImageSide a side, a constant frame) throws FrameRefused with its reason. A stamp before the
  /// previous one is not thrown: it comes back as FrameStatus::TimeJump (a caller may reset on it).
  /// With confirm_frames > 0 a frame that passes every rule comes back Pending, and the frame that confirms it
  /// carries it, Published, in `confirmed` (LoopConfirmation).
  FrameOutcome process(const FrameInput& input);

  /// The input's descriptor as the configuration says: stereo D-LDB from `disparity` or from the pair
  /// (SGBM), a ring from `cameras`, otherwise `image`. Throws Error naming what is missing, FrameRefused for
  /// an image too small or a constant frame.
  FrameDescriptor describe(const FrameInput& input) const;

  /// The camera for verification (rectified intrinsics; a baseline makes it stereo). The first valid one
  /// is kept; returns false (and keeps the first) when another is given. Throws Error when invalid.
  bool setCamera(const PinholeCamera& camera);
  bool hasVerifier() const
  {
    return verifier_ != nullptr;
  }
  const GeometricVerifier* verifier() const
  {
    return verifier_.get();
  }

  /// New values of the keys that can change live (LoopDetector::updateMatching plus the decision keys).
  /// Throws Error, changing nothing, when a verify_* key differs (the verifier is built once, in setCamera).
  void updateConfig(const Config& config);
  /// Forgets the stream (and, in loop-closure mode, the history and stored features).
  void reset();

  const Config& config() const
  {
    return config_;
  }
  const OnlineOptions& options() const
  {
    return options_;
  }
  const FrameDescriber& describer() const
  {
    return describer_;
  }
  const LoopDetector& loopDetector() const
  {
    return detector_;
  }
  const LoopConfirmation& confirmation() const
  {
    return confirmation_;
  }
  /// The view channel while it runs, else null.
  const ViewChannel* viewChannel() const
  {
    return views_on_ ? views_.get() : nullptr;
  }
  bool localisationMode() const
  {
    return detector_.localisationMode();
  }

private:
  /// process() but for the outcome's number.
  FrameOutcome processFrame(const FrameInput& input);
  std::vector<Patch> patches(const FrameInput& input) const;
  /// patches() of a frame that may become a place: refuses a constant frame (FrameRefused).
  std::vector<Patch> placePatches(const FrameInput& input) const;
  bool isKeyframe(const FrameInput& input);
  /// How still the camera is, judged on a textured frame (a textureless one, e.g. a tunnel, says nothing about
  /// motion and is Moving): Repeated within standstill_distance of the last stored frame, WithinNoise within
  /// stop_distance of it or of the still stretch's first frame (a real sensor flips a few bits a frame).
  enum class Stillness
  {
    Moving,
    WithinNoise,
    Repeated
  };
  Stillness stillness(const FrameDescriptor& descriptor, const std::vector<Patch>& cells) const;
  /// The input's views shifted left and right (Config::lateral_shift), one descriptor after the other, or none
  /// where there are none (no shift, a ring, a disparity descriptor).
  FrameDescriptor shiftedViews(const FrameDescriber& describer, const FrameInput& input) const;
  /// Builds the view channel where the configuration asks for one (a new stream, or the new session of an empty
  /// map), in the whole image's session.
  void startViewChannel();
  /// One channel's parts: the whole image's (detector_, decision_, confirmation_) or the view channel's.
  struct Channel
  {
    LoopDetector& detector;
    LoopDecision& decision;
    LoopConfirmation& confirmation;
  };
  /// Decides `outcome` (its detection made by the channel's detector), verifies what the decision asks, and hands
  /// it to the channel's confirmation: returns the earlier frames that it confirms.
  std::vector<FrameOutcome> decideAndConfirm(Channel channel, const FrameFeatures* query, FrameOutcome& outcome);
  /// The view channel's match of the frame being stored (its own descriptor and views), undecided.
  FrameOutcome matchViews(const FrameInput& input, const FrameOutcome& stored);
  /// Joins the two channels' outcomes of this frame and what each confirmed: a frame's first loop closure is kept
  /// (the whole image's where both come at once), a later one of the same frame dropped. `outcome` becomes the
  /// view channel's where that one took the frame further (decisionProgress).
  std::vector<FrameOutcome> joinChannels(FrameOutcome& outcome, std::vector<FrameOutcome> confirmed,
                                         const FrameOutcome& viewed, std::vector<FrameOutcome> view_confirmed);
  /// The input's verification features (options_.verify with a camera), or null (the note says why).
  std::unique_ptr<FrameFeatures> queryFeatures(const FrameInput& input, FrameOutcome& outcome) const;
  /// The best match's stored info (FrameOutcome::match), looked up by id: storing the query may have evicted it.
  void lookUpMatch(FrameOutcome& outcome) const;
  /// Verifies the best match against `query` into outcome.verification (verification_ran; when it cannot run,
  /// the note says why).
  void verifyBestMatch(const FrameFeatures* query, FrameOutcome& outcome) const;

  Config config_;
  OnlineOptions options_;
  FrameDescriber describer_;
  LoopDetector detector_;
  LoopDecision decision_;
  LoopConfirmation confirmation_;
  FrameMetric metric_;
  bool has_last_stored_ = false;
  FrameDescriptor last_stored_;  ///< the last stored frame's descriptor (standstill)
  FrameOutcome last_outcome_;    ///< and its outcome: a frame standing still repeats it
  FrameOutcome last_whole_outcome_;  ///< the whole image's channel's outcome of it (its confirmation's repeats;
                                     ///< last_outcome_ is the two channels' joined)
  FrameOutcome last_view_outcome_;   ///< the view channel's outcome of it
  std::unique_ptr<ViewChannel> views_;  ///< Config::view_channel_shift in loop-closure mode of a new stream
  bool views_on_ = false;               ///< views_ runs (off for a stream whose images have no views)
  /// Each of the last frames as it was reported (the view channel on), oldest first: its status, whose decision it
  /// was, and whether a loop closure went out for it. A loop closure the other channel confirms later moves its frame
  /// from that status (FrameOutcome::status_before); a second one of a frame is dropped (joinChannels).
  struct Reported
  {
    FrameStatus status;
    bool view_channel;
    bool published;
  };
  std::deque<Reported> reported_;
  /// Frames kept there: a loop closure comes at most LoopDecision::kMaxJoined stored frames late, each with its
  /// repeats (a standstill); 65,536 frames (about 2 h at 10 Hz) is beyond any run met, in under 1 MiB.
  static constexpr uint64_t kJoinFrames = uint64_t(1) << 16;
  FrameDescriptor still_anchor_;  ///< the last stored frame that was not within a still camera's noise (stop_distance)
  int still_frames_ = 0;          ///< stored frames in a row since still_anchor_ within that noise
  int frames_out_of_noise_ = 0;   ///< frames in a row out of that noise while stopped
  /// Frames in a row out of a still camera's noise that end a stop (the first may be a stray frame of the noise).
  static constexpr int kFramesThatEndAStop = 2;
  uint64_t frames_ = 0;          ///< frames given to process(): the next outcome's `frame`
  std::unique_ptr<GeometricVerifier> verifier_;
  FeatureStore features_;
  double last_stamp_ = 0.0;
  bool has_keyframe_pose_ = false;
  std::array<double, 7> keyframe_pose_{{0, 0, 0, 0, 0, 0, 1}};
};

}  // namespace openable
