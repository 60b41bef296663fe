#include "openable/atomic_file.h"
#include "openable/place_database.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/image_source.h"

namespace fs = std::filesystem;

namespace openable
{
namespace
{
constexpr char kMagic[8] = {'O', 'P', 'N', 'A', 'B', 'L', 'E', 'M'};
/// Version 2 (issue 11): no per-frame id (ids are consecutive from the first id), the pose only when the
/// frame has one. Version 1 maps still load.
constexpr uint32_t kVersion = 2;
constexpr size_t kAlignment = 64;

uint64_t fnv1a(const char* data, size_t size)
{
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < size; ++i)
  {
    hash ^= static_cast<uint8_t>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

/// Bytes of one frame's metadata in the file before its source name: id, stamp, session, pose flag, pose,
/// name length (version 1); stamp, session, pose flag, name length (version 2, the pose only when flagged).
constexpr size_t kFrameInfoBytesV1 = 8 + 8 + 4 + 1 + 7 * 8 + 8;
constexpr size_t kFrameInfoBytesV2 = 8 + 4 + 1 + 8;
/// A stored configuration is a few hundred bytes of YAML.
constexpr size_t kMaxConfigBytes = 1 << 20;

/// The whole file, read in one piece of exactly its size. Only regular files: a device (/dev/zero) or a
/// pipe has no size and would be read until memory runs out.
std::string readMapFile(const std::string& path)
{
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status))
    throw Error("cannot open map file '" + path + "' (missing or unreadable)");
  if (!fs::is_regular_file(status))
    throw Error("map file '" + path + "' is not a regular file; expected a map written by save_map or openable");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec || size > std::numeric_limits<size_t>::max() / 2)
    throw Error("cannot read the size of map file '" + path + "'");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error("cannot open map file '" + path + "'");
  std::string bytes(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(&bytes[0], static_cast<std::streamsize>(size)))
    throw Error("cannot read map file '" + path + "' (it changed or shrank while being read)");
  return bytes;
}

/// A map is only usable when its stored configuration can be compared with the running one, so an
/// unreadable one is refused here, as part of the file, not later by whoever reads it.
void checkStoredConfiguration(const std::string& yaml, const std::string& path)
{
  if (yaml.empty())
    return;
  try
  {
    Config::fromYamlString(yaml);
  }
  catch (const Error& e)
  {
    throw Error("map file '" + path + "' has an unreadable stored configuration: " + e.what());
  }
}

/// Appends plain values (the file format is little-endian, as every platform this runs on).
class Writer
{
public:
  template <typename T>
  void put(const T& value)
  {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void putBytes(const void* data, size_t size)
  {
    bytes_.append(static_cast<const char*>(data), size);
  }
  void putString(const std::string& s)
  {
    put<uint64_t>(s.size());
    bytes_ += s;
  }
  std::string& bytes()
  {
    return bytes_;
  }

private:
  std::string bytes_;
};

/// Reads plain values with bounds checks: a truncated file is an error, never a read past the end.
class Reader
{
public:
  Reader(const std::string& bytes, size_t end, const std::string& path) : bytes_(bytes), end_(end), path_(path) {}
  template <typename T>
  T get(const char* what)
  {
    T value;
    getBytes(&value, sizeof(T), what);
    return value;
  }
  void getBytes(void* out, size_t size, const char* what)
  {
    if (size > end_ - pos_)
      throw Error("map file '" + path_ + "' is truncated (while reading " + what + ")");
    std::memcpy(out, bytes_.data() + pos_, size);
    pos_ += size;
  }
  std::string getString(const char* what, size_t max_size)
  {
    const auto size = get<uint64_t>(what);
    if (size > max_size || size > end_ - pos_)
      throw Error("map file '" + path_ + "' is corrupt (" + what + " of " + std::to_string(size) + " bytes)");
    std::string s(bytes_.data() + pos_, size);
    pos_ += size;
    return s;
  }
  size_t remaining() const
  {
    return end_ - pos_;
  }

private:
  const std::string& bytes_;
  size_t end_;
  size_t pos_ = 0;
  const std::string& path_;
};
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
  const size_t bytes = (sizeof(uint64_t) * stride_ * frames + kAlignment - 1) / kAlignment * kAlignment;
  auto* data = static_cast<uint64_t*>(std::aligned_alloc(kAlignment, bytes));
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
  return sizeof(uint64_t) * stride_ * allocated_ + sizeof(FrameRecord) * records_.capacity() +
         sizeof(std::array<double, 7>) * poses_.capacity() + sources_.bytes();
}

void PlaceDatabase::shrinkToFit()
{
  records_.shrink_to_fit();
  poses_.shrink_to_fit();
  sources_.shrinkToFit();
  if (allocated_ == size() || size() == 0)
    return;
  const size_t bytes = (sizeof(uint64_t) * stride_ * size() + kAlignment - 1) / kAlignment * kAlignment;
  auto* data = static_cast<uint64_t*>(std::aligned_alloc(kAlignment, bytes));
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

void PlaceDatabase::save(const std::string& path) const
{
  Writer w;
  w.putBytes(kMagic, sizeof(kMagic));
  w.put<uint32_t>(kVersion);
  w.put<uint32_t>(layout_.binary ? 1 : 0);
  w.put<int32_t>(layout_.cell_length);
  w.put<int32_t>(layout_.cell_words);
  w.put<int32_t>(layout_.cells);
  w.put<int32_t>(layout_.blocks);
  w.put<uint64_t>(capacity_);
  w.put<uint64_t>(first_id_);
  w.put<uint64_t>(size());
  w.putString(config_yaml_);
  for (size_t i = 0; i < size(); ++i)
  {
    const FrameRecord& record = records_[i];
    w.put<double>(record.stamp);
    w.put<uint32_t>(record.session);
    w.put<uint8_t>(record.pose != kNoPose ? 1 : 0);
    if (record.pose != kNoPose)
      for (double v : poses_[record.pose])
        w.put<double>(v);
    w.putString(sources_.at(i));
  }
  if (size())
    w.putBytes(data_, sizeof(uint64_t) * stride_ * size());
  w.put<uint64_t>(fnv1a(w.bytes().data(), w.bytes().size()));
  writeFileAtomically(path, w.bytes());
}

PlaceDatabase PlaceDatabase::load(const std::string& path)
{
  const std::string bytes = readMapFile(path);
  if (bytes.size() < sizeof(kMagic) + sizeof(uint64_t) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    throw Error("'" + path + "' is not an openable_ros map file (wrong magic bytes)");
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t stored_checksum;
  std::memcpy(&stored_checksum, bytes.data() + body, sizeof(uint64_t));
  Reader r(bytes, body, path);
  char magic[sizeof(kMagic)];
  r.getBytes(magic, sizeof(magic), "magic");
  const auto version = r.get<uint32_t>("version");
  if (version != 1 && version != kVersion)
    throw Error("map file '" + path + "' has format version " + std::to_string(version) +
                "; this build reads versions 1 to " + std::to_string(kVersion) + " (a newer openable_ros wrote it?)");
  if (fnv1a(bytes.data(), body) != stored_checksum)
    throw Error("map file '" + path + "' is corrupt or truncated (checksum mismatch)");

  DescriptorLayout layout;
  layout.binary = r.get<uint32_t>("layout") != 0;
  layout.cell_length = r.get<int32_t>("layout");
  layout.cell_words = r.get<int32_t>("layout");
  layout.cells = r.get<int32_t>("layout");
  layout.blocks = r.get<int32_t>("layout");
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("map file '" + path + "' is corrupt (" + problem + ")");
  const auto capacity = r.get<uint64_t>("capacity");
  const auto first_id = r.get<uint64_t>("first id");
  const auto frames = r.get<uint64_t>("frame count");
  // The header's counts are bounded by the bytes that are really there before anything is allocated, so
  // a small crafted file cannot ask for gigabytes.
  const size_t info_bytes = version == 1 ? kFrameInfoBytesV1 : kFrameInfoBytesV2;
  if (frames > r.remaining() / (info_bytes + sizeof(uint64_t) * layout.frameWords()))
    throw Error("map file '" + path + "' is corrupt (frame count " + std::to_string(frames) + " does not fit its " +
                std::to_string(bytes.size()) + " bytes)");
  // add() keeps at most `capacity` frames; more than that would be written past the storage.
  if (capacity != 0 && frames > capacity)
    throw Error("map file '" + path + "' is corrupt (" + std::to_string(frames) + " frames exceed its capacity of " +
                std::to_string(capacity) + ")");
  PlaceDatabase db(layout, capacity, r.getString("configuration", kMaxConfigBytes));
  checkStoredConfiguration(db.config_yaml_, path);
  db.first_id_ = first_id;
  db.reserve(frames);
  for (uint64_t i = 0; i < frames; ++i)
  {
    FrameInfo info;
    // Version 1 stored every id; they were always consecutive (add() numbers frames), which version 2 relies on.
    if (version == 1 && r.get<uint64_t>("frame id") != first_id + i)
      throw Error("map file '" + path + "' is corrupt (frame ids are not consecutive from the first id " +
                  std::to_string(first_id) + ")");
    info.stamp = r.get<double>("stamp");
    info.session = r.get<uint32_t>("session");
    info.has_pose = r.get<uint8_t>("pose flag") != 0;
    if (version == 1 || info.has_pose)
      for (double& v : info.pose)
        v = r.get<double>("pose");
    info.source = r.getString("source name", 1 << 16);
    db.append(info);
  }
  if (frames)
    r.getBytes(db.data_, sizeof(uint64_t) * db.stride_ * frames, "descriptors");
  if (r.remaining() != 0)
    throw Error("map file '" + path + "' is corrupt (" + std::to_string(r.remaining()) + " unexpected bytes)");
  return db;
}

}  // namespace openable
