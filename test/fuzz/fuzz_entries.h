#pragma once

// The entry functions the libFuzzer targets (test/fuzz/fuzz_*.cpp) and the corpus replay test
// (test/core/test_fuzz_corpus.cpp) share: each feeds bytes to one loader the way a user's file would reach
// it. openable::Error is the expected way to refuse input and is swallowed; anything else (another
// exception, a crash, a sanitizer report) escapes and is a finding.

#include <cstddef>
#include <cstdint>

namespace openable_fuzz
{
/// The bytes as a map file: SessionMap::load (every format version), its stored configuration, and the map
/// continued by a detector when that configuration is valid and matches.
void loadMap(const uint8_t* data, size_t size);
/// The bytes as a YAML configuration: Config::fromYamlString, validate() and, when valid, a FrameDescriber.
void parseConfig(const uint8_t* data, size_t size);
/// The bytes as a .npy file: readNpy.
void readNpy(const uint8_t* data, size_t size);

}  // namespace openable_fuzz
