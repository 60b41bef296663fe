#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace openable
{
/// Estimated bytes per patch pixel while a frame is preprocessed: 3 (8-bit colour downsample) + 1 (grey)
/// + 4 (float intensity) + 4 (patch normalisation) + 4 (the patches cut out of it).
constexpr uint64_t kWorkingBytesPerPatchPixel = 16;
/// Generous bound on those images per frame: 1 GiB (64 Mpx of patches, e.g. a 64x64 grid of 128 px
/// patches). The defaults use 64 KiB; a 64x64 grid of 1024 px patches would need 64 GiB per frame and is
/// refused by validate() instead of failing in an allocation.
constexpr uint64_t kMaxWorkingBytesPerFrame = uint64_t(1) << 30;

/// camera_type, parsed.
enum class CameraType
{
  Mono,
  Stereo,
  Panoramic
};
/// description_type, parsed.
enum class DescriptionType
{
  Global,  ///< the whole image is one patch (per sub-panorama)
  Grid     ///< grid_x x grid_y patches
};

/// One rule a configuration breaks, as a value: the keys it involves (one, or each key of a rule across
/// keys), the value found and what was expected. message() is the text validate() gives.
struct ConfigProblem
{
  std::vector<std::string> keys;
  std::string value;
  std::string expected;

  /// "key: value 'x' is not allowed; expected ..." (the keys joined with '/').
  std::string message() const;
};

/// What Config::sanitized() did about one problem: the keys it reset to the fallback's values (none when
/// every key of the problem is one it may not reset).
struct ConfigRepair
{
  ConfigProblem problem;
  std::vector<std::string> reset_keys;
};

/// Every parameter of the toolbox. The same snake_case keys are used in YAML files, on the command line
/// (`--set key=value`) and as private ROS parameters of the nodelets. The member defaults are
/// config/default.yaml's values (a test keeps them equal), so a bare nodelet, `openable_offline` without
/// --config and a YAML that sets a few keys all mean "default.yaml with these changes". Config::paper() is the
/// OpenABLE paper's configuration (config/paper.yaml).
struct Config
{
  /// The paper's values: LDB, single images, no acceptance gate, the first pass's pace only. Publishes
  /// nothing by itself (no gate is set); reproduces the paper's matrices.
  static Config paper();
  /// The view channel's configuration (view_channel_shift): this one with lateral_shift = view_channel_shift,
  /// descriptor_bits = view_channel_bits (a binary descriptor's), view_channel_consistent_frames and no view channel
  /// of its own.
  Config viewChannel() const;

  // Camera and description.
  std::string camera_type = "mono";         ///< mono | stereo | panoramic
  std::string description_type = "global";  ///< global | grid
  int patch_size = 64;                      ///< side of the square patch each cell is downsampled to (pixels)
  int grid_x = 1;                           ///< cells across (description_type grid)
  int grid_y = 1;                           ///< cells down (description_type grid)
  int panoramas = 6;                        ///< sub-panoramas per panoramic image (camera_type panoramic)
  bool illumination_invariance = false;     ///< paper Eq. 6 before description (needs colour input)
  double alpha = 0.47;                      ///< alpha of Eq. 6 (0.47 for KITTI's Flea2, see Eq. 7)
  int patch_normalization = 0;              ///< block side for local contrast normalisation of patches (0 = off)
  /// Fraction of the image width a revisit may see the scene shifted sideways (a camera on the other side of the
  /// path, or turned a little): a place is described from the image's centre, 1 - 2 x lateral_shift of its width,
  /// and a query frame also shifted that far left and right; its distance to a place is the smallest of the three
  /// (the pace matcher, max_pace > 1; the diagonal sums compare the centres). 0 = the whole image, no shift.
  /// Mono images and a stereo camera's left image with a mono descriptor; not a panorama (matched at every
  /// rotation already) nor a disparity descriptor (D-LDB: the disparity is not shifted with the image).
  double lateral_shift = 0.0;
  std::string descriptor = "HOG-B";         ///< LDB | D-LDB | BRIEF | BRISK | ORB | FREAK | HOG-B | SIFT | SURF | HOG
  /// A binary descriptor keeps this many of its bits, evenly spread over them (0 = all): fewer bytes a place.
  int descriptor_bits = 0;
  /// A second channel (0 = off): the image's centre crop, 1 - 2 x this of the width, matched with the frame's
  /// views shifted left and right (as lateral_shift does), with its own sequences, decision and confirmation. A
  /// frame's loop closure is the first either channel publishes (the whole image's when both come at once): the
  /// other side of a path found without losing what the whole image finds (a faster pace). Loop-closure mode of a
  /// new stream, on
  /// images that have views (mono, or a stereo camera's left image with a mono descriptor; not a panorama, not
  /// D-LDB, not with lateral_shift); maps, sessions and localisation hold and use the whole image's channel alone.
  double view_channel_shift = 0.12;
  int view_channel_bits = 128;  ///< descriptor_bits of that channel's places (0 = all; a float descriptor keeps all)
  /// consistent_frames of that channel (0 = consistent_frames): its distances, the smallest of three views on fewer
  /// bits, are noisier, and a run of wrong matches holds together longer.
  int view_channel_consistent_frames = 12;

  // Matching.
  int sequence_length = 30;     ///< L: a place is the sequence of the last L frames
  int min_sequence_length = 1;  ///< sequences with fewer frames are not candidates (0 = only full, L, sequences)
  /// Loop-closure mode: sequences of fewer frames (at most L) are not candidates (0 = only full sequences of L).
  int min_loop_sequence_length = 21;
  double threshold = -1.0;      ///< accept a loop when the normalised distance is <= threshold; -1 = no gate
  int exclusion_window = 50;    ///< loop-closure mode: the last N frames before the current one are never matched
  /// Loop-closure mode: while the stream's own map holds at most 2 x exclusion_window + sequence_length frames, its
  /// own candidates come from a second matcher that leaves out only this many recent frames (a route walked again
  /// sooner than exclusion_window frames: a corridor, a small room); -1 = off (also when >= exclusion_window).
  int short_map_exclusion = 30;
  int top_k = 5;                ///< candidates reported per frame
  double min_uniqueness = 0.06; ///< accept only when 1 - best/second best >= this (0 = off)
  int uniqueness_window = 10;   ///< frames around the best match ignored when looking for the second best
  bool bidirectional = false;   ///< also match sequences driven in the opposite direction
  int max_history = 0;          ///< frames kept in the loop-closure history (0 = unbounded)
  int max_pace = 3;             ///< places a revisit may advance per frame: 1 = the first pass's pace (diagonal
                                ///< sums); > 1 = any pace from a stop to max_pace (PaceMatcher)
  double pace_penalty = 3.0;    ///< PaceMatcher: cost of a change of pace, in standard deviations of a
                                ///< sequence's distance under noise
  double slip_penalty = 0.35;   ///< PaceMatcher: cost of a sequence moving one place off its line in a frame, as a
                                ///< fraction of pace_penalty (0 = never); divided by sqrt(pace) on a line above 1x
  int pace_tolerance = 0;       ///< PaceMatcher: places a sequence may be off its line in each frame (0..2)
  int screen_places = 131072;   ///< PaceMatcher: a row of more places is screened, every pace's costs kept only
                                ///< where the screen ranks first (0 = never screened)
  double pace_prior = 0.24;     ///< PaceMatcher: while no loop is published, what a pace 30 % or more from the first
                                ///< pass's pays to be a place's best (a fraction of pace_penalty; less nearer 1x)
  double standstill_distance = 0.002;  ///< a frame this close (normalised) to the last stored one is the camera
                                     ///< standing still: not stored, not matched (0 = off)
  double stop_distance = 0.025;  ///< a frame this close (normalised) to the first frame of a still stretch, or to the
                                ///< last stored one, is within a still camera's noise (0 = off)
  int stop_frames = 25;          ///< after this many such frames in a row, the next ones are a stop: not stored, not
                                ///< matched, no loop closure (a real camera at a red light)

  // Loop-closure decision (OnlineDetector): what must hold, besides the gates above, before a loop is published.
  int min_candidates = 21;         ///< fewer candidate places: "too early" (2 x uniqueness_window + 1 places)
  int consistent_frames = 10;      ///< this many consecutive frames must pass the gates with matches advancing
                                   ///< together (1 = off)
  int consistency_tolerance = 2;   ///< frames a match may deviate from advancing one place per frame
  double continue_uniqueness = 0.03;  ///< a published run goes on through frames this unique (below
                                      ///< min_uniqueness) whose matches keep to its line (>= min_uniqueness: off)
  /// Once a run is consistent, the frames before it (its first frames, and not-unique ones before them) whose
  /// matches lie within this many places of its line, extended back, are published too, late, with their own
  /// stamps (-1 = off: a run's first consistent_frames - 1 frames are lost).
  int run_start_tolerance = 1;
  /// Frames after a published run's last frame during which a frame on its line, extended (within
  /// consistency_tolerance), at continue_uniqueness, resumes it (0 = off).
  int run_resume_frames = 30;
  /// A frame is not a loop closure where the places around its best match look alike: the median over its last
  /// LoopDecision::kReliefFrames frames of Detection::relief (their own distances to the places within
  /// uniqueness_window of the match, largest minus smallest, in standard deviations of the row) below this
  /// (0 = off; needs max_pace > 1).
  double min_relief = 1.0;
  int confirm_frames = 3;  ///< a loop closure is published once this many more stored frames go on with its run
                           ///< (0 = at once; LoopConfirmation)
  /// With geometric verification: a frame below min_uniqueness (or with fewer than min_candidates places) joins
  /// its run when verification accepts its best match and its uniqueness is at least this; the run must still be
  /// consistent (-1 = off: verification only checks what appearance published).
  double verified_min_uniqueness = 0.02;
  bool verification_veto = true;  ///< with verification: a loop closure it rejects is not published
                                  ///< (false: appearance alone decides it, published without a relative pose)
  double exclusion_seconds = 0.0;  ///< loop-closure mode: frames stamped less than this before the query are
                                   ///< never matched (0 = off; the frame window still applies)

  // Stereo (camera_type stereo): OpenCV StereoSGBM on the rectified pair, scaled to the input width.
  int stereo_num_disparities = 64;  ///< disparity search range at 640 px width (multiple of 16 after scaling)
  int stereo_block_size = 5;        ///< SGBM block size (odd, pixels)

  // Display.
  std::string display_normalization = "minmax";  ///< distance matrix images: max (paper Eq. 5) | minmax (stretch)
  int color_map = 7;  ///< OpenABLE's 12 colour maps (0..11, OpenCV COLORMAP_AUTUMN .. COLORMAP_HOT)

  // Geometric verification (~verify / openable_offline --camera-info): the GeometricVerifier's tunables,
  // VerifierParams field by field (verifierParams() in geometric_verifier.h; the defaults are its defaults).
  // They neither change the descriptors nor can change live.
  int verify_max_features = 1000;                 ///< ORB features per frame
  double verify_ratio = 0.8;                      ///< Lowe ratio: best / second-best Hamming distance below this
  int verify_max_hamming = 64;                    ///< a feature match with more differing bits (of 256) is discarded
  int verify_min_inliers = 15;                    ///< fewer RANSAC inliers (or matches, or keypoints): rejected
  double verify_ransac_threshold_px = 2.0;        ///< inlier threshold: reprojection (stereo) or Sampson (mono) error
  double verify_ransac_confidence = 0.999;        ///< RANSAC confidence
  int verify_ransac_iterations = 2000;            ///< PnP RANSAC iterations
  double verify_min_parallax_deg = 2.0;           ///< mono: less median parallax is pure rotation (rejected)
  double verify_identical_max_flow_px = 0.5;      ///< less median inlier motion is the same image twice (rejected)
  double verify_stereo_max_row_diff_px = 2.0;     ///< stereo depth: |y_left - y_right| allowed at octave 0
  double verify_stereo_min_disparity_px = 1.0;    ///< stereo depth: smaller disparity (too far) gives no depth
  double verify_stereo_max_disparity_px = 160.0;  ///< stereo depth: larger disparity gives no depth
  int verify_stereo_max_hamming = 50;             ///< stereo depth: left/right descriptor distance allowed
  int verify_min_stereo_points = 30;              ///< stereo: fewer match-frame keypoints with depth: rejected

  /// Every rule this configuration breaks; empty when valid. Besides each key's range, refuses
  /// combinations whose images need more than kMaxWorkingBytesPerFrame per frame.
  std::vector<ConfigProblem> problems() const;
  /// problems() as text, one "key: value 'x' is not allowed; expected ..." each.
  std::vector<std::string> validate() const;
  /// This configuration repaired key by key: every key a broken rule names is reset to `fallback`'s value,
  /// rule after rule (a reset can resolve, or expose, a rule across two keys); keys in `fixed` are never
  /// reset. `repairs` receives what was done, problem by problem. The result is valid when its problems()
  /// is empty, which it may not be when a `fixed` key breaks a rule or `fallback` is itself invalid.
  Config sanitized(const Config& fallback, std::vector<ConfigRepair>& repairs,
                   const std::vector<std::string>& fixed = {}) const;
  /// Bytes of the images one frame is turned into before description (workingBytesPerFrame = cells x
  /// patch_size^2 x kWorkingBytesPerPatchPixel; the 8-bit colour downsample, its grey and float copies, the
  /// float patches cut from it). 64 KiB for the defaults.
  uint64_t workingBytesPerFrame() const;
  /// Throws openable::Error with every validation error joined, when there are any.
  void validateOrThrow() const;

  /// Sets one key from its text form (as in YAML or `--set key=value`). Throws Error for an unknown key
  /// (listing the known ones) or a value of the wrong type. Does not validate ranges: call validate().
  void set(const std::string& key, const std::string& value);
  /// The text form of one key's value. Throws Error for an unknown key.
  std::string get(const std::string& key) const;

  /// Reads every key present in a YAML mapping; unknown keys are an error. Throws Error.
  static Config fromYamlFile(const std::string& path);
  static Config fromYamlString(const std::string& yaml);
  /// The whole configuration as YAML (used to stamp saved maps and outputs).
  std::string toYaml() const;

  /// Keys whose change alters the descriptors (the `describes` ones; a map built with other values is
  /// incompatible).
  static const std::vector<std::string>& descriptorKeys();

  /// The schema of one key: everything that lists keys (YAML, --set, ROS parameters, dynamic_reconfigure's
  /// cfg/Detector.cfg, the documentation) derives from or is tested against this table.
  struct Key
  {
    std::string name;
    std::string type;  ///< bool | int | double | string
    std::string description;
    double min = 0.0;            ///< numbers: smallest allowed value (with has_range)
    double max = 0.0;            ///< numbers: largest allowed value (with has_range)
    bool has_range = false;      ///< min/max hold (rules across keys are in problems())
    bool minus_one_is_off = false;  ///< with has_range [-1, max]: -1 turns the key off, (-1, 0) is not allowed
    bool min_exclusive = false;  ///< with has_range: min itself is not allowed, (min, max]
    bool max_exclusive = false;  ///< with has_range: max itself is not allowed, [min, max)
    bool live = false;           ///< can change while running (LoopDetector::updateMatching, dynamic_reconfigure)
    bool describes = false;      ///< changes the descriptors: a map built with another value is incompatible
  };
  /// Every key, in documentation order.
  static const std::vector<Key>& keys();
  /// Keys that can change while running (the `live` ones), in documentation order.
  static const std::vector<std::string>& liveKeys();

  /// camera_type and description_type as enums. Throw Error for a word validate() refuses.
  CameraType camera() const;
  DescriptionType description() const;
};

/// A Config that passed validation, made once where a configuration enters (OnlineDetector, a tool, a
/// nodelet): the modules built from one (FrameDescriber, LoopDetector) trust it and do not validate again.
class ValidConfig
{
public:
  /// Throws Error with every problem when `config` is invalid.
  explicit ValidConfig(Config config);

  const Config& operator*() const
  {
    return config_;
  }
  const Config* operator->() const
  {
    return &config_;
  }

private:
  Config config_;
};

/// The candidate with the smallest edit distance to `name` (for "did you mean" messages); "" when empty.
std::string closestName(const std::string& name, const std::vector<std::string>& candidates);

/// Paper Eq. 7: alpha from the peak spectral responses (nm) of the red, green and blue channels.
double alphaFromWavelengths(double lambda_red, double lambda_green, double lambda_blue);

}  // namespace openable
