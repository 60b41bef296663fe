#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace openable
{
/// The source name of every stored frame (file name, topic), front-coded so that a name costs the bytes it
/// does not share with the previous one: consecutive files of one folder ("…/Image041.jpg", "…/Image042.jpg")
/// take ~7 bytes each, frames of one topic 2. Every kBlock-th name is stored whole (a restart point), so
/// at() decodes at most kBlock names. Names are kept in the order they were added; the oldest leave first.
class SourceNames
{
public:
  static constexpr size_t kBlock = 16;

  void push_back(const std::string& name);
  /// Name by position (0 = oldest kept). Throws Error past the end.
  std::string at(size_t position) const;
  size_t size() const
  {
    return size_;
  }
  /// Forgets the `count` oldest names (re-encodes the rest: O(size), as evicting descriptors is).
  void dropOldest(size_t count);
  void clear();
  void shrinkToFit();
  /// Heap bytes held (capacities, not sizes).
  size_t bytes() const;

private:
  std::string encoded_;           ///< per name: varint shared prefix length, varint suffix length, suffix
  std::vector<uint64_t> blocks_;  ///< offset in encoded_ of every kBlock-th name (stored whole)
  std::string last_;              ///< the newest name, to front-code the next one
  size_t size_ = 0;
};

}  // namespace openable
