#include "openable/map/place_database.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "map/map_file.h"
#include "openable/error.h"
#include "openable/map/streamed_block.h"

namespace openable
{
namespace
{
/// A block for `bytes` of descriptors (a descriptor row starts a cache line when the stride is a multiple of 8
/// words); null when out of memory. Freed with std::free.
uint64_t* allocateDescriptors(size_t bytes)
{
  return static_cast<uint64_t*>(allocateStreamedBlock(bytes));
}
}  // namespace

PlaceDatabase::PlaceDatabase(const DescriptorLayout& layout, size_t capacity, std::string config_yaml)
  : layout_(layout), stride_(layout.frameWords()), capacity_(capacity), config_yaml_(std::move(config_yaml))
{
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("PlaceDatabase: unsupported descriptor " + problem);
}

PlaceDatabase::PlaceDatabase(const PlaceDatabase& other)
  : layout_(other.layout_),
    stride_(other.stride_),
    capacity_(other.capacity_),
    config_yaml_(other.config_yaml_),
    first_id_(other.first_id_),
    records_(other.records_),
    poses_(other.poses_),
    sources_(other.sources_)
{
  reserve(other.size());
  if (other.size())
    std::memcpy(data_, other.data_, sizeof(uint64_t) * stride_ * other.size());
}

PlaceDatabase::PlaceDatabase(PlaceDatabase&& other) noexcept
  : layout_(other.layout_), stride_(other.stride_), capacity_(other.capacity_)
{
  swap(*this, other);
}

PlaceDatabase& PlaceDatabase::operator=(PlaceDatabase other)
{
  swap(*this, other);
  return *this;
}

PlaceDatabase::~PlaceDatabase()
{
  std::free(data_);
}

void swap(PlaceDatabase& a, PlaceDatabase& b) noexcept
{
  using std::swap;
  swap(a.layout_, b.layout_);
  swap(a.stride_, b.stride_);
  swap(a.capacity_, b.capacity_);
  swap(a.config_yaml_, b.config_yaml_);
  swap(a.first_id_, b.first_id_);
  swap(a.records_, b.records_);
  swap(a.poses_, b.poses_);
  swap(a.sources_, b.sources_);
  swap(a.data_, b.data_);
  swap(a.allocated_, b.allocated_);
}

void PlaceDatabase::reserve(size_t frames)
{
  if (frames <= allocated_)
    return;
  auto* data = allocateDescriptors(sizeof(uint64_t) * stride_ * frames);
  if (!data)
    throw Error("PlaceDatabase: out of memory for " + std::to_string(frames) + " frames");
  if (data_)
    std::memcpy(data, data_, sizeof(uint64_t) * stride_ * size());
  std::free(data_);
  data_ = data;
  allocated_ = frames;
  records_.reserve(frames);  // the records grow with the descriptors, not by a policy of their own
}

size_t PlaceDatabase::pendingEviction() const
{
  if (capacity_ == 0 || size() < capacity_)
    return 0;
  return std::max<size_t>(1, capacity_ / 16);
}

uint64_t PlaceDatabase::add(const uint64_t* descriptor, size_t words, FrameInfo info)
{
  if (words != stride_)
    throw Error("descriptor of " + std::to_string(words) + " words does not fit the database layout of " +
                std::to_string(stride_) + " words");
  evictOldest(pendingEviction());
  if (size() == allocated_)
  {
    size_t grown = std::max<size_t>(64, allocated_ * 2);
    if (capacity_)
      grown = std::min(grown, capacity_);
    reserve(grown);
  }
  std::memcpy(data_ + size() * stride_, descriptor, sizeof(uint64_t) * stride_);
  const uint64_t id = first_id_ + size();
  append(info);
  return id;
}

void PlaceDatabase::append(const FrameInfo& info)
{
  FrameRecord record;
  record.stamp = info.stamp;
  record.session = info.session;
  if (info.has_pose)
  {
    record.pose = static_cast<uint32_t>(poses_.size());
    poses_.push_back(info.pose);
  }
  records_.push_back(record);
  sources_.push_back(info.source);
}

FrameInfo PlaceDatabase::info(size_t position) const
{
  const FrameRecord& record = records_.at(position);
  FrameInfo info;
  info.id = first_id_ + position;
  info.stamp = record.stamp;
  info.session = record.session;
  info.has_pose = record.pose != kNoPose;
  if (info.has_pose)
    info.pose = poses_[record.pose];
  info.source = sources_.at(position);
  return info;
}

void PlaceDatabase::evictOldest(size_t count)
{
  count = std::min(count, size());
  if (count == 0)
    return;
  std::memmove(data_, data_ + count * stride_, sizeof(uint64_t) * stride_ * (size() - count));
  // Poses are stored in frame order: the evicted frames' poses are the oldest ones.
  uint32_t dropped_poses = 0;
  for (size_t i = 0; i < count; ++i)
    dropped_poses += records_[i].pose != kNoPose;
  records_.erase(records_.begin(), records_.begin() + static_cast<long>(count));
  if (dropped_poses)
  {
    poses_.erase(poses_.begin(), poses_.begin() + dropped_poses);
    for (FrameRecord& record : records_)
      if (record.pose != kNoPose)
        record.pose -= dropped_poses;
  }
  sources_.dropOldest(count);
  first_id_ += count;
}

size_t PlaceDatabase::bytes() const
{
  return (allocated_ ? streamedBlockBytes(sizeof(uint64_t) * stride_ * allocated_) : 0) +
         sizeof(FrameRecord) * records_.capacity() + sizeof(std::array<double, 7>) * poses_.capacity() +
         sources_.bytes();
}

void PlaceDatabase::shrinkToFit()
{
  records_.shrink_to_fit();
  poses_.shrink_to_fit();
  sources_.shrinkToFit();
  if (allocated_ == size() || size() == 0)
    return;
  auto* data = allocateDescriptors(sizeof(uint64_t) * stride_ * size());
  if (!data)
    return;  // keeping the larger block is correct, only less lean
  std::memcpy(data, data_, sizeof(uint64_t) * stride_ * size());
  std::free(data_);
  data_ = data;
  allocated_ = size();
}

void PlaceDatabase::clear()
{
  first_id_ += size();
  records_.clear();
  poses_.clear();
  sources_.clear();
}

void PlaceDatabase::renumber(uint64_t first_id)
{
  first_id_ = first_id;
}

void PlaceDatabase::save(const std::string& path) const
{
  const SessionInfo session{"session 0", "", size() ? stamp(0) : 0.0};
  map_file::write(path, layout_, config_yaml_, {map_file::SessionView{&session, this}});
}

PlaceDatabase PlaceDatabase::load(const std::string& path)
{
  map_file::Contents contents = map_file::read(path);
  if (contents.frames.size() != 1)
    throw Error("map file '" + path + "' holds " + std::to_string(contents.frames.size()) +
                " sessions; expected one here (load it as a SessionMap)");
  return std::move(contents.frames.front());
}

}  // namespace openable
