#include "openable/io/source_names.h"

#include <algorithm>

#include "openable/error.h"

namespace openable
{
namespace
{
void putVarint(std::string& out, size_t value)
{
  while (value >= 0x80)
  {
    out.push_back(static_cast<char>((value & 0x7f) | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<char>(value));
}

size_t getVarint(const std::string& in, size_t& pos)
{
  size_t value = 0;
  for (int shift = 0;; shift += 7)
  {
    const auto byte = static_cast<uint8_t>(in[pos++]);
    value |= size_t(byte & 0x7f) << shift;
    if (!(byte & 0x80))
      return value;
  }
}
}  // namespace

void SourceNames::push_back(const std::string& name)
{
  size_t shared = 0;
  if (size_ % kBlock == 0)
    blocks_.push_back(encoded_.size());
  else
    while (shared < name.size() && shared < last_.size() && name[shared] == last_[shared])
      ++shared;
  putVarint(encoded_, shared);
  putVarint(encoded_, name.size() - shared);
  encoded_.append(name, shared, std::string::npos);
  last_ = name;
  ++size_;
}

std::string SourceNames::at(size_t position) const
{
  if (position >= size_)
    throw Error("source name " + std::to_string(position) + " of " + std::to_string(size_) + " requested");
  size_t pos = blocks_[position / kBlock];
  std::string name;
  for (size_t i = position / kBlock * kBlock; i <= position; ++i)
  {
    const size_t shared = getVarint(encoded_, pos);
    const size_t suffix = getVarint(encoded_, pos);
    name.resize(shared);
    name.append(encoded_, pos, suffix);
    pos += suffix;
  }
  return name;
}

void SourceNames::dropOldest(size_t count)
{
  count = std::min(count, size_);
  if (count == 0)
    return;
  SourceNames kept;
  for (size_t i = count; i < size_; ++i)
    kept.push_back(at(i));
  std::swap(*this, kept);
}

void SourceNames::clear()
{
  *this = SourceNames();
}

void SourceNames::shrinkToFit()
{
  encoded_.shrink_to_fit();
  blocks_.shrink_to_fit();
}

size_t SourceNames::bytes() const
{
  // Heap only: a string's bytes within its small-string buffer are part of the object.
  const auto heap = [](const std::string& s) { return s.capacity() > 15 ? s.capacity() + 1 : 0; };
  return heap(encoded_) + heap(last_) + sizeof(uint64_t) * blocks_.capacity();
}

}  // namespace openable
