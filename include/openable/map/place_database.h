#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "openable/descriptors/descriptor_layout.h"
#include "openable/io/source_names.h"

namespace openable
{
/// What is known about one stored frame besides its descriptor, as add() takes it and info() returns it. The
/// database keeps less (see PlaceDatabase): the id is implicit, the source name and the pose live in tables
/// of their own.
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
/// A stored frame costs its descriptor plus a 16-byte record (stamp, session, pose index; the id is
/// firstId() + position) plus its source name front-coded (SourceNames: a few bytes for consecutive files of
/// one folder or frames of one topic); frames with a pose also hold 56 bytes in the pose table.
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
    return records_.size();
  }
  bool empty() const
  {
    return records_.empty();
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
  /// The frame's metadata, assembled from the record and the tables (the source name is decoded).
  FrameInfo info(size_t position) const;
  /// The stamp alone, without decoding the source name.
  double stamp(size_t position) const
  {
    return records_[position].stamp;
  }

  /// Gives the stored frames ids from `first_id` on (a map merged after another continues its ids).
  void renumber(uint64_t first_id);
  /// Keeps room for `frames` frames without growing again.
  void reserve(size_t frames);

  /// Bytes held by descriptors and metadata (capacities: what the process holds).
  size_t bytes() const;
  /// Releases the room kept for frames not added yet (a reference map that no longer grows).
  void shrinkToFit();

  void clear();

  /// The map file of SessionMap (versioned, checksummed, written atomically) with this one session.
  /// Throws Error.
  void save(const std::string& path) const;
  /// A map file of one session (any format version). Throws Error naming what is wrong: missing, not a
  /// map, unsupported version, truncated, checksum, or several sessions (use SessionMap::load).
  static PlaceDatabase load(const std::string& path);

  PlaceDatabase(const PlaceDatabase& other);
  PlaceDatabase& operator=(PlaceDatabase other);
  PlaceDatabase(PlaceDatabase&& other) noexcept;
  ~PlaceDatabase();

private:
  /// One stored frame's metadata as kept. 16 bytes: the id is implicit, the source name sits at the same
  /// position in sources_, the pose in poses_.
  struct FrameRecord
  {
    double stamp = 0.0;
    uint32_t session = 0;
    uint32_t pose = kNoPose;  ///< index into poses_
  };
  static constexpr uint32_t kNoPose = UINT32_MAX;

  void evictOldest(size_t count);
  void append(const FrameInfo& info);
  friend void swap(PlaceDatabase& a, PlaceDatabase& b) noexcept;

  DescriptorLayout layout_;
  size_t stride_ = 0;  ///< words per frame
  size_t capacity_ = 0;
  std::string config_yaml_;
  uint64_t first_id_ = 0;
  std::vector<FrameRecord> records_;
  std::vector<std::array<double, 7>> poses_;
  SourceNames sources_;
  uint64_t* data_ = nullptr;  ///< 64-byte aligned, allocated_ frames
  size_t allocated_ = 0;
};

}  // namespace openable
