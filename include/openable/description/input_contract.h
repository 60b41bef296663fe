#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "openable/error.h"
#include "openable/description/preprocessor.h"

namespace openable
{
/// What may enter the library, the same for every entry (nodelets, place server, offline tools, map and
/// pose files), and the refusal of what may not. Each refusal has its own short reason (for counting and
/// log throttles) and a message saying what was wrong and what was expected.
///
/// - A pose (x y z qx qy qz qw) is finite and its quaternion has a norm within kQuaternionTolerance of 1;
///   it is then normalised. A zero, non-finite or clearly non-unit quaternion is refused.
/// - A stamp (seconds) is finite and not negative. Within one stream: stamps never go back, and a stream
///   that has had a stamp never gets 0 again (0 is "unset" in ROS headers: a backend placing edges by stamp
///   cannot use it). A stream whose first frame is stamped 0 has no stamps at all (folders of images).
/// - A frame described as a place is at least kMinImageSide pixels a side, and shows something: some cell
///   has a grey-level spread of at least kMinFrameStdDev (an all-black or constant frame is no place),
///   unless the illumination-invariant image is used, where a dark frame is legitimate.
class InputRefused : public Error
{
public:
  /// `reason` is a short key for counting ("pose", "stamp 0", "image too small", ...); `what` names the
  /// value and what was expected.
  InputRefused(std::string reason, const std::string& what) : Error(what), reason_(std::move(reason)) {}
  const std::string& reason() const
  {
    return reason_;
  }

private:
  std::string reason_;
};

/// A frame the detector does not describe as a place. Nothing was stored.
class FrameRefused : public InputRefused
{
public:
  using InputRefused::InputRefused;
};

using Pose = std::array<double, 7>;  ///< x y z qx qy qz qw

/// How far the norm of a quaternion may be from 1 to be normalised rather than refused: 7-digit pose
/// files and float32 messages are within 1e-6; a norm off by more than 1 % is no rotation someone meant.
constexpr double kQuaternionTolerance = 0.01;
/// Smallest side of an image that is described as a place (a 1-pixel strip has no place in it).
constexpr int kMinImageSide = 16;
/// Grey levels (0..255) of spread below which a patch shows nothing: a black tunnel frame is the same
/// descriptor at any speed (standstill), and an all-zero frame is no place at all.
constexpr double kMinTextureStdDev = 2.0;
/// Below this spread in every cell the frame is constant (all black, all grey): refused as a place. Lower
/// than kMinTextureStdDev: a dark tunnel frame of the Nordland data still has a spread of a few levels and
/// is matched as usual.
constexpr double kMinFrameStdDev = 0.5;

/// What is wrong with something that came in: empty when nothing.
struct InputProblem
{
  std::string reason;  ///< short key, as InputRefused::reason()
  std::string what;    ///< what was wrong and what was expected
  bool ok() const
  {
    return reason.empty();
  }
};

/// Checks `pose` and normalises its quaternion in place when it is accepted.
InputProblem checkPose(Pose& pose);
/// Throws InputRefused (reason from checkPose) prefixed by `who` ("robot 'r1'", "file.txt:3").
Pose validPose(const Pose& pose, const std::string& who);

/// The stamp rule of one stream: `previous` is the last accepted stamp; `stream_has_stamps` when the stream
/// has had a stamp; `require_stamps` refuses 0 even as the first stamp (ROS streams: 0 is unset). A stamp
/// before `previous` gives reason "stamp went backwards".
InputProblem checkStamp(double stamp, double previous, bool stream_has_stamps, bool require_stamps = false);

/// True when some cell's intensity has a grey-level spread of at least `min_std_dev`.
bool textured(const std::vector<Patch>& cells, double min_std_dev);
/// Empty when the image is large enough to be a place (kMinImageSide a side).
InputProblem checkImageSize(int width, int height);
/// Empty when the frame's cells show something (kMinFrameStdDev); every frame passes when
/// `illumination_invariance` is on (a dark frame is legitimate there).
InputProblem checkTexture(const std::vector<Patch>& cells, bool illumination_invariance);

}  // namespace openable
