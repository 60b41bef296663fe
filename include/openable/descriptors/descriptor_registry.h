// Every descriptor the library offers, one row each: what the rest of the library knows of a descriptor
// without building one (its name, form, length, whether it needs stereo disparity, the smallest patch it
// can describe) and the factory that builds it. Names, validation, the D-LDB rule and a frame's descriptor
// layout are all derived from these rows; adding a descriptor is a row here and a file in
// src/core/descriptors/ (doc/architecture.md, "Where to add things").
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "openable/descriptors/descriptor_extractor.h"

namespace openable
{
enum class DescriptorForm
{
  Binary,  ///< bits, compared by Hamming distance
  Float    ///< float values, scaled to unit length and compared by L2 distance
};

/// One descriptor.
struct DescriptorInfo
{
  const char* name;       ///< the `descriptor` key's value, e.g. "HOG-B"
  DescriptorForm form;
  int length;             ///< bits (binary) or floats (float) per patch; the same for every patch size
  bool needs_disparity;   ///< describes the disparity patch too: camera_type stereo only
  int min_patch_size;     ///< smallest patch side it can describe
  /// Builds the extractor for one patch size (>= min_patch_size).
  std::unique_ptr<DescriptorExtractor> (*create)(int patch_size);

  bool binary() const
  {
    return form == DescriptorForm::Binary;
  }
};

/// The rows, in the order the documentation lists them.
const std::vector<DescriptorInfo>& descriptorRegistry();

/// The row named `name`; nullptr when there is none.
const DescriptorInfo* findDescriptor(const std::string& name);

/// The row named `name`. Throws Error naming the valid descriptors when there is none.
const DescriptorInfo& descriptorInfo(const std::string& name);

/// The names of every row, in registry order.
std::vector<std::string> descriptorNames();

}  // namespace openable
