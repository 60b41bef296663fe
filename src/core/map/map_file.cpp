#include "map/map_file.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

#include "openable/io/atomic_file.h"
#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/input_contract.h"

namespace fs = std::filesystem;

namespace openable
{
namespace map_file
{
namespace
{
constexpr char kMagic[8] = {'O', 'P', 'N', 'A', 'B', 'L', 'E', 'M'};
/// Version 3 (issue 12): a table of sessions, each with its own frames and ids. Version 2 (issue 11): no
/// per-frame id, the pose only when the frame has one. Version 1: every field of every frame.
constexpr uint32_t kVersion = 3;

/// Bytes of one frame's metadata before its source name: id, stamp, session, pose flag, pose, name length
/// (version 1); stamp, session, pose flag, name length (versions 2 and 3, the pose only when flagged).
constexpr size_t kFrameInfoBytesV1 = 8 + 8 + 4 + 1 + 7 * 8 + 8;
constexpr size_t kFrameInfoBytesV2 = 8 + 4 + 1 + 8;
/// The smallest session entry: name and robot lengths, start stamp, capacity, first id, frame count.
constexpr size_t kSessionBytes = 6 * 8;
/// A stored configuration is a few hundred bytes of YAML; names are short.
constexpr size_t kMaxConfigBytes = 1 << 20;
constexpr size_t kMaxNameBytes = 1 << 16;
/// Sessions a map may hold: one per robot run, years of a fleet's runs. Names are compared with every
/// earlier one on load, so the cap also bounds that cost.
constexpr uint32_t kMaxSessions = 1 << 14;

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

/// The whole file, read in one piece of exactly its size. Only regular files: a device (/dev/zero) or a
/// pipe has no size and would be read until memory runs out.
std::string readWholeFile(const std::string& path)
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
  const std::string& path() const
  {
    return path_;
  }

private:
  const std::string& bytes_;
  size_t end_;
  size_t pos_ = 0;
  const std::string& path_;
};

void putLayout(Writer& w, const DescriptorLayout& layout)
{
  w.put<uint32_t>(layout.binary ? 1 : 0);
  w.put<int32_t>(layout.cell_length);
  w.put<int32_t>(layout.cell_words);
  w.put<int32_t>(layout.cells);
  w.put<int32_t>(layout.blocks);
}

DescriptorLayout getLayout(Reader& r)
{
  DescriptorLayout layout;
  layout.binary = r.get<uint32_t>("layout") != 0;
  layout.cell_length = r.get<int32_t>("layout");
  layout.cell_words = r.get<int32_t>("layout");
  layout.cells = r.get<int32_t>("layout");
  layout.blocks = r.get<int32_t>("layout");
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("map file '" + r.path() + "' is corrupt (" + problem + ")");
  return layout;
}

/// One session's frames: capacity, first id, count, every frame's metadata, then the descriptors.
void putFrames(Writer& w, const PlaceDatabase& frames)
{
  w.put<uint64_t>(frames.capacity());
  w.put<uint64_t>(frames.firstId());
  w.put<uint64_t>(frames.size());
  for (size_t i = 0; i < frames.size(); ++i)
  {
    const FrameInfo info = frames.info(i);
    w.put<double>(info.stamp);
    w.put<uint32_t>(info.session);
    w.put<uint8_t>(info.has_pose ? 1 : 0);
    if (info.has_pose)
      for (double v : info.pose)
        w.put<double>(v);
    w.putString(info.source);
  }
  if (frames.size())
    w.putBytes(frames.data(), sizeof(uint64_t) * frames.layout().frameWords() * frames.size());
}

PlaceDatabase getFrames(Reader& r, uint32_t version, const DescriptorLayout& layout, const std::string& config_yaml,
                        size_t capacity, uint64_t first_id, uint64_t frames)
{
  const std::string& path = r.path();
  const size_t words = layout.frameWords();
  // The header's counts are bounded by the bytes that are really there before anything is allocated, so
  // a small crafted file cannot ask for gigabytes.
  const size_t info_bytes = version == 1 ? kFrameInfoBytesV1 : kFrameInfoBytesV2;
  if (frames > r.remaining() / (info_bytes + sizeof(uint64_t) * words))
    throw Error("map file '" + path + "' is corrupt (frame count " + std::to_string(frames) +
                " does not fit the bytes left in the file)");
  // add() keeps at most `capacity` frames; more than that would be written past the storage.
  if (capacity != 0 && frames > capacity)
    throw Error("map file '" + path + "' is corrupt (" + std::to_string(frames) + " frames exceed its capacity of " +
                std::to_string(capacity) + ")");
  std::vector<FrameInfo> infos(frames);
  for (uint64_t i = 0; i < frames; ++i)
  {
    FrameInfo& info = infos[i];
    // Version 1 stored every id; they were always consecutive (add() numbers frames), which later versions rely on.
    if (version == 1 && r.get<uint64_t>("frame id") != first_id + i)
      throw Error("map file '" + path + "' is corrupt (frame ids are not consecutive from the first id " +
                  std::to_string(first_id) + ")");
    info.stamp = r.get<double>("stamp");
    info.session = r.get<uint32_t>("session");
    info.has_pose = r.get<uint8_t>("pose flag") != 0;
    if (version == 1 || info.has_pose)
      for (double& v : info.pose)
        v = r.get<double>("pose");
    info.source = r.getString("source name", kMaxNameBytes);
    // The input contract holds for what a file brings too (poses a backend would receive, stamps).
    const InputProblem pose = info.has_pose ? checkPose(info.pose) : InputProblem();
    if (!pose.ok())
      throw Error("map file '" + path + "' is corrupt (frame " + std::to_string(first_id + i) + ": " + pose.what + ")");
    if (!std::isfinite(info.stamp) || info.stamp < 0.0)
      throw Error("map file '" + path + "' is corrupt (frame " + std::to_string(first_id + i) + ": stamp " +
                  std::to_string(info.stamp) + "; expected finite seconds >= 0)");
  }
  PlaceDatabase db(layout, capacity, config_yaml);
  db.renumber(first_id);
  if (frames == 0)
    return db;  // nothing allocated: an empty session costs its table entry, whatever the layout declares
  db.reserve(frames);
  std::vector<uint64_t> descriptor(words);
  for (uint64_t i = 0; i < frames; ++i)
  {
    r.getBytes(descriptor.data(), sizeof(uint64_t) * words, "descriptors");
    db.add(descriptor.data(), words, std::move(infos[i]));
  }
  return db;
}

/// Formats 1 and 2: one database (header, configuration, frames), read as one session.
void readSingleSession(Reader& r, uint32_t version, Contents& contents)
{
  contents.layout = getLayout(r);
  const auto capacity = r.get<uint64_t>("capacity");
  const auto first_id = r.get<uint64_t>("first id");
  const auto frames = r.get<uint64_t>("frame count");
  contents.config_yaml = r.getString("configuration", kMaxConfigBytes);
  checkStoredConfiguration(contents.config_yaml, r.path());
  contents.sessions.push_back(SessionInfo{"session 0", "", 0.0});
  contents.frames.push_back(getFrames(r, version, contents.layout, contents.config_yaml, capacity, first_id, frames));
  if (!contents.frames.back().empty())
    contents.sessions.back().start_stamp = contents.frames.back().stamp(0);
}

void readSessions(Reader& r, Contents& contents)
{
  contents.layout = getLayout(r);
  contents.config_yaml = r.getString("configuration", kMaxConfigBytes);
  checkStoredConfiguration(contents.config_yaml, r.path());
  const auto count = r.get<uint32_t>("session count");
  if (count > kMaxSessions)
    throw Error("map file '" + r.path() + "' declares " + std::to_string(count) + " sessions; at most " +
                std::to_string(kMaxSessions) + " are supported (one a robot run)");
  if (count > r.remaining() / kSessionBytes)
    throw Error("map file '" + r.path() + "' is corrupt (session count " + std::to_string(count) +
                " does not fit the file)");
  contents.sessions.reserve(count);
  contents.frames.reserve(count);
  std::set<std::string> names;
  for (uint32_t s = 0; s < count; ++s)
  {
    SessionInfo info;
    info.name = r.getString("session name", kMaxNameBytes);
    info.robot = r.getString("robot name", kMaxNameBytes);
    info.start_stamp = r.get<double>("session start");
    const auto capacity = r.get<uint64_t>("capacity");
    const auto first_id = r.get<uint64_t>("first id");
    const auto frames = r.get<uint64_t>("frame count");
    if (!names.insert(info.name).second)
      throw Error("map file '" + r.path() + "' is corrupt (session name '" + info.name + "' twice)");
    contents.sessions.push_back(std::move(info));
    contents.frames.push_back(getFrames(r, kVersion, contents.layout, contents.config_yaml, capacity, first_id, frames));
  }
}
}  // namespace

void write(const std::string& path, const DescriptorLayout& layout, const std::string& config_yaml,
           const std::vector<SessionView>& sessions)
{
  Writer w;
  w.putBytes(kMagic, sizeof(kMagic));
  w.put<uint32_t>(kVersion);
  putLayout(w, layout);
  w.putString(config_yaml);
  w.put<uint32_t>(static_cast<uint32_t>(sessions.size()));
  for (const SessionView& session : sessions)
  {
    w.putString(session.info->name);
    w.putString(session.info->robot);
    w.put<double>(session.info->start_stamp);
    putFrames(w, *session.frames);
  }
  w.put<uint64_t>(fnv1a(w.bytes().data(), w.bytes().size()));
  writeFileAtomically(path, w.bytes());
}

Contents read(const std::string& path)
{
  const std::string bytes = readWholeFile(path);
  if (bytes.size() < sizeof(kMagic) + sizeof(uint64_t) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    throw Error("'" + path + "' is not an openable_ros map file (wrong magic bytes)");
  const size_t body = bytes.size() - sizeof(uint64_t);
  uint64_t stored_checksum;
  std::memcpy(&stored_checksum, bytes.data() + body, sizeof(uint64_t));
  Reader r(bytes, body, path);
  char magic[sizeof(kMagic)];
  r.getBytes(magic, sizeof(magic), "magic");
  const auto version = r.get<uint32_t>("version");
  if (version < 1 || version > kVersion)
    throw Error("map file '" + path + "' has format version " + std::to_string(version) +
                "; this build reads versions 1 to " + std::to_string(kVersion) + " (a newer openable_ros wrote it?)");
  if (fnv1a(bytes.data(), body) != stored_checksum)
    throw Error("map file '" + path + "' is corrupt or truncated (checksum mismatch)");
  Contents contents;
  if (version < 3)
    readSingleSession(r, version, contents);
  else
    readSessions(r, contents);
  if (r.remaining() != 0)
    throw Error("map file '" + path + "' is corrupt (" + std::to_string(r.remaining()) + " unexpected bytes)");
  return contents;
}

}  // namespace map_file
}  // namespace openable
