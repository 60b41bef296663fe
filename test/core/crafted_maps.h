#pragma once
// Issue 22, finding 4: small crafted maps that declare much (../shared/repro/make_many_empty_sessions_map.py,
// in C++): the tests of what loading them may cost, in the core and in the tools.

#include <cstdint>
#include <string>

namespace openable_test
{
template <typename T>
inline void put(std::string& bytes, T value)
{
  bytes.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

inline void putString(std::string& bytes, const std::string& s)
{
  put<uint64_t>(bytes, s.size());
  bytes += s;
}

/// A version-3 map of `sessions` empty sessions with a binary layout of 22-word (1386-bit) cells, `cells`
/// of them a frame (762600 cells: 2^24 words, the largest layout a map may declare).
inline std::string emptySessionsMap(uint32_t sessions, int32_t cells = 762600, const std::string& config_yaml = "")
{
  std::string bytes = "OPNABLEM";
  put<uint32_t>(bytes, 3);
  put<uint32_t>(bytes, 1);
  put<int32_t>(bytes, 1386);
  put<int32_t>(bytes, 22);
  put<int32_t>(bytes, cells);
  put<int32_t>(bytes, 1);
  putString(bytes, config_yaml);
  put<uint32_t>(bytes, sessions);
  for (uint32_t s = 0; s < sessions; ++s)
  {
    putString(bytes, "s" + std::to_string(s));
    putString(bytes, "r");
    put<double>(bytes, 0.0);
    put<uint64_t>(bytes, 0);  // capacity
    put<uint64_t>(bytes, 0);  // first id
    put<uint64_t>(bytes, 0);  // frames
  }
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes)
  {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  put<uint64_t>(bytes, hash);
  return bytes;
}

}  // namespace openable_test
