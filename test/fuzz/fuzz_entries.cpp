#include "fuzz_entries.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <limits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/description/input_contract.h"
#include "openable/detection/loop_detector.h"
#include "openable/detection/online_detector.h"
#include "openable/server/candidate_merger.h"
#include "openable/server/place_server.h"
#include "openable/io/npy.h"
#include "openable/map/session_map.h"

namespace openable_fuzz
{
namespace
{
/// The loaders take paths, and their size and file-type checks are part of what is tested: the bytes go
/// through a file of this process's own.
class TemporaryFile
{
public:
  TemporaryFile(const uint8_t* data, size_t size, const char* extension)
    : path_((std::filesystem::temp_directory_path() / ("openable_fuzz_" + std::to_string(::getpid()) + extension))
                .string())
  {
    FILE* file = std::fopen(path_.c_str(), "wb");
    if (!file)
      throw openable::Error("fuzz: cannot write " + path_);
    if (size > 0)
      std::fwrite(data, 1, size, file);
    std::fclose(file);
  }
  ~TemporaryFile()
  {
    std::remove(path_.c_str());
  }
  const std::string& path() const
  {
    return path_;
  }

private:
  std::string path_;
};

/// The map format ends with an FNV-1a checksum of everything before it. Random mutations would almost
/// never get past it, so the last 8 bytes are replaced by the right checksum: inputs then reach the parser
/// (the checksum check itself is covered by test_place_database).
std::string withValidChecksum(const uint8_t* data, size_t size)
{
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.size() < sizeof(uint64_t))
    return bytes;
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < body; ++i)
  {
    hash ^= static_cast<uint8_t>(bytes[i]);
    hash *= 0x100000001b3ULL;
  }
  bytes.replace(body, sizeof(uint64_t), reinterpret_cast<const char*>(&hash), sizeof(uint64_t));
  return bytes;
}

/// Reads the formats of placeMessages and detectorFrames: little-endian, a field past the end reads as 0.
class ByteReader
{
public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool done() const
  {
    return at_ >= size_;
  }
  size_t remaining() const
  {
    return size_ - std::min(at_, size_);
  }
  uint64_t unsignedOf(size_t bytes)
  {
    uint64_t v = 0;
    for (size_t i = 0; i < bytes; ++i, ++at_)
      if (at_ < size_)
        v |= uint64_t(data_[at_]) << (8 * i);
    return v;
  }
  uint8_t u8()
  {
    return uint8_t(unsignedOf(1));
  }
  uint16_t u16()
  {
    return uint16_t(unsignedOf(2));
  }
  uint32_t u32()
  {
    return uint32_t(unsignedOf(4));
  }
  uint64_t u64()
  {
    return unsignedOf(8);
  }
  float f32()
  {
    const uint32_t bits = u32();
    float v;
    std::memcpy(&v, &bits, sizeof(v));
    return v;
  }
  double f64()
  {
    const uint64_t bits = u64();
    double v;
    std::memcpy(&v, &bits, sizeof(v));
    return v;
  }
  std::string str()
  {
    const size_t n = std::min<size_t>(u8(), remaining());
    std::string s(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return s;
  }
  /// Up to `n` bytes (fewer at the end), consumed.
  std::vector<uint8_t> take(size_t n)
  {
    n = std::min(n, remaining());
    std::vector<uint8_t> out(data_ + at_, data_ + at_ + n);
    at_ += n;
    return out;
  }
  std::array<double, 7> pose()
  {
    std::array<double, 7> p;
    for (double& v : p)
      v = f64();
    return p;
  }

private:
  const uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
};

/// A configuration the entries build themselves: invalid would be a bug of the entry, not a finding.
openable::Config checked(const openable::Config& config)
{
  const auto problems = config.validate();
  if (!problems.empty())
    throw std::logic_error("fuzz entry: invalid configuration: " + problems.front());
  return config;
}

/// Short sequences and few rivals: a handful of frames reach matching and decisions.
openable::Config quickConfig()
{
  openable::Config c;
  c.sequence_length = 3;
  c.min_candidates = 2;
  c.exclusion_window = 2;
  c.uniqueness_window = 1;
  c.consistent_frames = 1;
  return c;
}

const openable::Config& placeConfig()
{
  static const openable::Config config = checked(quickConfig());
  return config;
}

openable::Config detectorConfig(int choice)
{
  openable::Config c = quickConfig();
  if (choice == 1)
  {
    c.description_type = "grid";
    c.grid_x = 2;
    c.grid_y = 2;
    c.descriptor = "LDB";
    c.patch_size = 32;
    c.illumination_invariance = true;
    c.patch_normalization = 8;
  }
  else if (choice == 2)
  {
    c.camera_type = "stereo";
    c.descriptor = "D-LDB";
  }
  return checked(c);
}

/// Uses a loaded map the way a detector would: continued as a new session, the first stored frame matched
/// against every session.
void useMap(const openable::SessionMap& map)
{
  const openable::Config config = openable::Config::fromYamlString(map.configYaml());
  if (map.frameCount() == 0 || !config.validate().empty())
    return;
  uint32_t session = 0;
  while (map.frames(session).empty())
    ++session;
  const openable::PlaceDatabase& frames = map.frames(session);
  const openable::FrameDescriptor first(frames.descriptor(0), frames.descriptor(0) + map.layout().frameWords());
  openable::LoopDetector detector(config, map, openable::MapMode::Continue, openable::SessionInfo{"fuzz", "", 0.0});
  detector.process(first);
}
}  // namespace

void loadMap(const uint8_t* data, size_t size)
{
  const std::string bytes = withValidChecksum(data, size);
  const TemporaryFile file(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), ".map");
  try
  {
    useMap(openable::SessionMap::load(file.path()));
  }
  catch (const openable::Error&)
  {
  }
}

void parseConfig(const uint8_t* data, size_t size)
{
  try
  {
    const openable::Config config =
        openable::Config::fromYamlString(std::string(reinterpret_cast<const char*>(data), size));
    if (config.validate().empty())
      openable::FrameDescriber describer(config);
  }
  catch (const openable::Error&)
  {
  }
}

void readNpy(const uint8_t* data, size_t size)
{
  const TemporaryFile file(data, size, ".npy");
  try
  {
    openable::readNpy(file.path());
  }
  catch (const openable::Error&)
  {
  }
}

namespace
{
openable::PlaceDescriptorInput descriptorMessage(ByteReader& in, uint8_t kind, size_t words)
{
  openable::PlaceDescriptorInput m;
  m.robot = in.str();
  m.session = in.str();
  if (kind & 16)
    m.topic_robot = in.str();
  m.frame_id = in.u64();
  m.stamp = in.f64();
  m.config_hash = (kind & 2) ? openable::descriptorHash(placeConfig()) : in.u64();
  const size_t n = (kind & 4) ? words : in.u8();
  m.descriptor.resize(n);
  for (uint64_t& w : m.descriptor)
    w = in.u64();
  m.has_pose = (kind & 8) != 0;
  if (m.has_pose)
    m.pose = in.pose();
  return m;
}

openable::ServerCandidates candidatesMessage(ByteReader& in, uint8_t kind)
{
  openable::ServerCandidates a;
  a.server = in.str();
  a.query_session = in.str();
  a.query_robot = in.str();
  a.query_frame = in.u64();
  a.query_stamp = in.f64();
  a.stored = in.u8() & 1;
  a.query_id = in.u64();
  a.candidates = in.u32();
  a.own_excluded = in.u8() & 1;
  a.other_frames = in.u32();
  a.has_query_pose = (kind & 8) != 0;
  if (a.has_query_pose)
    a.query_pose = in.pose();
  const size_t top = std::min<size_t>(in.u8(), 8);
  for (size_t i = 0; i < top; ++i)
  {
    openable::ServerCandidate c;
    c.session = in.str();
    c.id = in.u64();
    c.distance = in.f32();
    c.direction = int8_t(in.u8());
    c.shift = int16_t(in.u16());
    c.sequence_length = in.u16();
    c.stamp = in.f64();
    c.has_pose = in.u8() & 1;
    if (c.has_pose)
      c.pose = in.pose();
    a.top.push_back(c);
  }
  return a;
}

template <typename F>
void refusedIsFine(F&& f)
{
  try
  {
    f();
  }
  catch (const openable::Error&)  // InputRefused (DescriptorRefused, FrameRefused) included
  {
  }
}
}  // namespace

size_t placeMessages(const uint8_t* data, size_t size)
{
  ByteReader in(data, size);
  const uint8_t flags = in.u8();
  const openable::Config& config = placeConfig();
  static const size_t words = openable::FrameDescriber(config).layout().frameWords();
  std::vector<std::string> owned;
  if (flags & 1)
    owned.push_back("r1");
  openable::PlaceServer server(config, owned, "fuzz");
  openable::CandidateMerger merger(config);
  openable::ServerCandidates last;
  bool has_last = false;
  size_t accepted = 0;
  for (int i = 0; i < 64 && !in.done(); ++i)
  {
    const uint8_t kind = in.u8();
    if (kind & 1)
    {
      openable::ServerCandidates answer = candidatesMessage(in, kind);
      refusedIsFine([&] { merger.merge({answer}); });
      if (has_last)
      {
        // Another server's answer to the query this server just saw.
        answer.query_session = last.query_session;
        answer.query_frame = last.query_frame;
        refusedIsFine([&] { merger.merge({last, answer}); });
      }
      continue;
    }
    const openable::PlaceDescriptorInput message = descriptorMessage(in, kind, words);
    refusedIsFine(
        [&]
        {
          last = server.process(message);
          has_last = true;
          ++accepted;
          merger.merge({last});
        });
  }
  return accepted;
}

size_t detectorFrames(const uint8_t* data, size_t size)
{
  ByteReader in(data, size);
  const int choice = in.u8() % 3;
  const uint8_t flags = in.u8();
  static const openable::Config configs[3] = {detectorConfig(0), detectorConfig(1), detectorConfig(2)};
  openable::OnlineOptions options;
  options.require_stamps = (flags & 1) != 0;
  options.keyframe_distance = (flags & 2) ? 0.5 : 0.0;
  openable::OnlineDetector detector(configs[choice], options);
  size_t processed = 0;
  for (int i = 0; i < 12 && !in.done(); ++i)
  {
    const int width = std::max<int>(1, in.u16());
    int height = std::max<int>(1, in.u16());
    height = std::max(1, std::min(height, 65536 / width));
    const int channels = (in.u8() & 1) ? 3 : 1;
    openable::FrameInput input;
    input.stamp = in.f64();
    input.has_pose = in.u8() & 1;
    if (input.has_pose)
      input.pose = in.pose();
    const uint8_t disparity_mode = in.u8() % 4;
    const std::vector<uint8_t> bytes = in.take(in.u32());
    input.image = cv::Mat(height, width, channels == 3 ? CV_8UC3 : CV_8UC1, cv::Scalar::all(0));
    const size_t total = input.image.total() * input.image.elemSize();
    if (!bytes.empty())
      for (size_t k = 0; k < total; ++k)
        input.image.data[k] = bytes[k % bytes.size()];
    if (choice == 2)
    {
      input.disparity = cv::Mat(height, width, CV_32F);
      for (int r = 0; r < height; ++r)
        for (int c = 0; c < width; ++c)
        {
          float& d = input.disparity.at<float>(r, c);
          const size_t k = (size_t(r) * size_t(width) + size_t(c)) * sizeof(float);
          if (disparity_mode == 0 && bytes.size() >= sizeof(float))
          {
            uint8_t raw[sizeof(float)];
            for (size_t b = 0; b < sizeof(float); ++b)
              raw[b] = bytes[(k + b) % bytes.size()];
            std::memcpy(&d, raw, sizeof(float));
          }
          else if (disparity_mode == 1)
            d = std::numeric_limits<float>::quiet_NaN();
          else if (disparity_mode == 2)
            d = std::numeric_limits<float>::infinity();
          else
            d = 1.0f + float(c % 64);
        }
    }
    try
    {
      detector.process(input);
      ++processed;
    }
    catch (const openable::Error&)  // FrameRefused included
    {
    }
  }
  return processed;
}

const openable::Config& placeMessagesConfig()
{
  return placeConfig();
}

openable::Config detectorFramesConfig(int choice)
{
  return detectorConfig(choice);
}

void ByteWriter::u8(uint8_t v)
{
  bytes_.push_back(char(v));
}
void ByteWriter::u16(uint16_t v)
{
  raw(&v, sizeof(v));
}
void ByteWriter::u32(uint32_t v)
{
  raw(&v, sizeof(v));
}
void ByteWriter::u64(uint64_t v)
{
  raw(&v, sizeof(v));
}
void ByteWriter::f32(float v)
{
  raw(&v, sizeof(v));
}
void ByteWriter::f64(double v)
{
  raw(&v, sizeof(v));
}
void ByteWriter::str(const std::string& s)
{
  const size_t n = std::min<size_t>(s.size(), 255);
  u8(uint8_t(n));
  bytes_.append(s, 0, n);
}
void ByteWriter::raw(const void* data, size_t size)
{
  // The formats are little-endian; every machine this builds on is.
  bytes_.append(static_cast<const char*>(data), size);
}

}  // namespace openable_fuzz
