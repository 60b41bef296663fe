#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "openable/frame_describer.h"

namespace openable
{
/// What is known about one stored frame besides its descriptor.
struct FrameInfo
{
  uint64_t id = 0;        ///< global index: the n-th frame ever added (kept across eviction and save/load)
  double stamp = 0.0;     ///< seconds (ROS time or the image's time); 0 when unknown
  uint32_t session = 0;   ///< session (traversal) id, for maps recorded over several runs
  std::string source;     ///< file name, topic or anything that names where the frame came from
  bool has_pose = false;  ///< pose of the camera in a fixed frame, when known
  std::array<double, 7> pose{{0, 0, 0, 0, 0, 0, 1}};  ///< x y z qx qy qz qw
};

/// Contiguous, 64-byte aligned descriptor storage (frame after frame, layout.frameWords() words each) with
/// per-frame metadata and an optional capacity bound.
///
/// When full, the oldest frames leave first, in batches of capacity/16 (at least one) so that the
/// storage stays contiguous without moving it on every frame: between 15/16 of the capacity and the whole
/// of it is kept.
class PlaceDatabase
{
public:
  /// capacity 0 = unbounded. config_yaml is stored with the map and checked on load by the caller.
  explicit PlaceDatabase(const DescriptorLayout& layout, size_t capacity = 0, std::string config_yaml = "");

  const DescriptorLayout& layout() const
  {
    return layout_;
  }
  size_t capacity() const
  {
    return capacity_;
  }
  size_t size() const
  {
    return infos_.size();
  }
  bool empty() const
  {
    return infos_.empty();
  }
  /// Global id of the oldest stored frame (0 until something was evicted).
  uint64_t firstId() const
  {
    return first_id_;
  }
  const std::string& configYaml() const
  {
    return config_yaml_;
  }

  /// Frames that add() will evict before storing the next frame (0 when there is room).
  size_t pendingEviction() const;

  /// Appends a frame (its id is set to firstId() + size()). Evicts pendingEviction() frames first.
  /// Returns the id. Throws Error when the descriptor length does not fit the layout.
  uint64_t add(const uint64_t* descriptor, size_t words, FrameInfo info = FrameInfo());
  uint64_t add(const FrameDescriptor& descriptor, FrameInfo info = FrameInfo())
  {
    return add(descriptor.data(), descriptor.size(), std::move(info));
  }

  /// Descriptor and metadata by position (0 = oldest stored frame).
  const uint64_t* descriptor(size_t position) const
  {
    return data_ + position * stride_;
  }
  const uint64_t* data() const
  {
    return data_;
  }
  const FrameInfo& info(size_t position) const
  {
    return infos_[position];
  }

  /// Bytes held by descriptors and metadata.
  size_t bytes() const;

  void clear();

  /// Versioned binary file: header (magic, version, layout, counts), the configuration YAML, metadata,
  /// descriptors, and a 64-bit checksum of everything before it. Written to a temporary file in the same
  /// folder and renamed over `path`, so a crash never leaves a partial map. Throws Error.
  void save(const std::string& path) const;
  /// Throws Error naming what is wrong: missing, not a map, unsupported version, truncated, checksum.
  static PlaceDatabase load(const std::string& path);

  PlaceDatabase(const PlaceDatabase& other);
  PlaceDatabase& operator=(PlaceDatabase other);
  PlaceDatabase(PlaceDatabase&& other) noexcept;
  ~PlaceDatabase();

private:
  void reserve(size_t frames);
  void evictOldest(size_t count);
  friend void swap(PlaceDatabase& a, PlaceDatabase& b) noexcept;

  DescriptorLayout layout_;
  size_t stride_ = 0;  ///< words per frame
  size_t capacity_ = 0;
  std::string config_yaml_;
  uint64_t first_id_ = 0;
  std::vector<FrameInfo> infos_;
  uint64_t* data_ = nullptr;  ///< 64-byte aligned, allocated_ frames
  size_t allocated_ = 0;
};

}  // namespace openable
