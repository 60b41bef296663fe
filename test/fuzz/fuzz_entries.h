#pragma once

// The entry functions the libFuzzer targets (test/fuzz/fuzz_*.cpp) and the corpus replay test
// (test/core/test_fuzz_corpus.cpp) share: each feeds bytes to one loader the way a user's file would reach
// it. openable::Error is the expected way to refuse input and is swallowed; anything else (another
// exception, a crash, a sanitizer report) escapes and is a finding.

#include <cstddef>
#include <cstdint>
#include <string>

#include "openable/config.h"

namespace openable_fuzz
{
/// The bytes as a map file: SessionMap::load (every format version), its stored configuration, and the map
/// continued by a detector when that configuration is valid and matches.
void loadMap(const uint8_t* data, size_t size);
/// The bytes as a YAML configuration: Config::fromYamlString, validate() and, when valid, a FrameDescriber.
void parseConfig(const uint8_t* data, size_t size);
/// The bytes as a .npy file: readNpy.
void readNpy(const uint8_t* data, size_t size);

/// The bytes as a stream of place messages, what the ROS place server and merger receive from the network
/// after openable_ros::toInput / fromMsg (field for field copies, no checks of their own): PlaceDescriptor
/// messages into one PlaceServer (HOG-B, L = 3), and PlaceCandidates answers (other servers') into a
/// CandidateMerger, alone and together with the local server's answer to the same query. DescriptorRefused
/// and Error are the accepted refusals. Returns the messages the server accepted (the replay test checks
/// that the real seeds get that far). Format (little-endian, a field past the end reads as 0):
///   u8 flags (bit 0: the server owns only session "r1")
///   then up to 64 messages, each:
///     u8 kind: bit 0 candidates answer (else a descriptor); bit 1 the right config hash (else u64 follows
///              the names); bit 2 the right descriptor length (else u8 word count); bit 3 has_pose;
///              bit 4 a topic robot is given
///     descriptor: str robot, str session, [str topic_robot], u64 frame_id, f64 stamp, [u64 hash],
///                 [u8 words], words x u64, [7 x f64 pose]
///     candidates: str server, str query_session, str query_robot, u64 query_frame, f64 stamp, u8 stored,
///                 u64 query_id, u32 candidates, u8 own_excluded, u32 other_frames, [7 x f64 pose],
///                 u8 top count (<= 8), each: str session, u64 id, f32 distance, i8 direction, i16 shift,
///                 u16 sequence_length, f64 stamp, u8 has_pose, [7 x f64 pose]
///   str: u8 length, then the bytes.
size_t placeMessages(const uint8_t* data, size_t size);

/// The bytes as images with stamps and poses through OnlineDetector::process, as the detector nodelets
/// call it after toCoreImage (CV_8UC1 or CV_8UC3 of any size) and tf (any pose, NaN and inf included).
/// FrameRefused and Error are the accepted refusals; a cv::Exception or anything else is a finding.
/// Returns the frames processed without refusal. Format (little-endian, a field past the end reads as 0):
///   u8 configuration (% 3): 0 mono HOG-B global, 1 mono LDB 2x2 grid with illumination invariance and
///      patch normalisation, 2 stereo D-LDB from a disparity image; all with L = 3 and few candidates
///   u8 options: bit 0 require_stamps (the nodelets' setting), bit 1 keyframe_distance 0.5 m
///   then up to 12 frames, each:
///     u16 width, u16 height (1..65535 each, width x height capped at 65536 by lowering the height),
///     u8 channels (bit 0: 3, else 1), f64 stamp, u8 has_pose, [7 x f64 pose],
///     u8 disparity (configuration 2: 0 from the bytes as floats, 1 NaN, 2 inf, 3 a ramp of 1..64),
///     u32 byte count n, then n pixel bytes (fewer when the input ends), repeated to fill the image
///     (zeros when n is 0)
size_t detectorFrames(const uint8_t* data, size_t size);

/// The configuration of placeMessages' server (its descriptors: FrameDescriber of it) and of
/// detectorFrames' `choice`.
const openable::Config& placeMessagesConfig();
openable::Config detectorFramesConfig(int choice);

/// The writers of the two formats above, for the seed corpus (write_seeds.cpp).
class ByteWriter
{
public:
  void u8(uint8_t v);
  void u16(uint16_t v);
  void u32(uint32_t v);
  void u64(uint64_t v);
  void f32(float v);
  void f64(double v);
  void str(const std::string& s);
  void raw(const void* data, size_t size);
  const std::string& bytes() const
  {
    return bytes_;
  }

private:
  std::string bytes_;
};

}  // namespace openable_fuzz
