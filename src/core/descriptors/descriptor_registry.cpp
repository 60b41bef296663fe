// The one table of descriptors. A new descriptor: its file in this folder (the class and a
// `create<Name>(int patch_size)` function, as hog_binary.cpp), its row below, its line in CMakeLists.txt.
// test_descriptors checks every row against the extractor it builds (form, length, smallest patch).
#include "openable/descriptors/descriptor_registry.h"

#include "descriptors/descriptor_implementations.h"
#include "openable/descriptors/ldb.h"
#include "openable/error.h"

namespace openable
{
// Factories of descriptors whose class lives in its own file only.
std::unique_ptr<DescriptorExtractor> createHogBinary(int patch_size);

namespace
{
template <class Extractor>
std::unique_ptr<DescriptorExtractor> create(int patch_size)
{
  return std::make_unique<Extractor>(patch_size);
}

// LDB and D-LDB keep one pattern for every patch size: the patch is resampled to it.
template <class Extractor>
std::unique_ptr<DescriptorExtractor> createFixed(int)
{
  return std::make_unique<Extractor>();
}

constexpr auto kBinary = DescriptorForm::Binary;
constexpr auto kFloat = DescriptorForm::Float;
}  // namespace

const std::vector<DescriptorInfo>& descriptorRegistry()
{
  // name, form, length (bits or floats), needs disparity, smallest patch, factory
  static const std::vector<DescriptorInfo> rows = {
      {"LDB", kBinary, kLdbBits, false, 10, &createFixed<LdbExtractor>},
      {"D-LDB", kBinary, 2 * kLdbBits, true, 10, &createFixed<DldbExtractor>},
      {"BRIEF", kBinary, BriefExtractor::kBits, false, 8, &create<BriefExtractor>},
      {"BRISK", kBinary, 512, false, 16, &create<BriskExtractor>},
      {"ORB", kBinary, 256, false, 16, &create<OrbExtractor>},
      {"FREAK", kBinary, FreakExtractor::kBits, false, 8, &create<FreakExtractor>},
      {"SIFT", kFloat, 128, false, 16, &create<SiftExtractor>},
      {"SURF", kFloat, SurfExtractor::kLength, false, 8, &create<SurfExtractor>},
      {"HOG", kFloat, HogExtractor::kLength, false, 8, &create<HogExtractor>},
      {"HOG-B", kBinary, HogExtractor::kLength, false, 8, &createHogBinary},
  };
  return rows;
}

const DescriptorInfo* findDescriptor(const std::string& name)
{
  for (const auto& row : descriptorRegistry())
    if (name == row.name)
      return &row;
  return nullptr;
}

const DescriptorInfo& descriptorInfo(const std::string& name)
{
  if (const DescriptorInfo* row = findDescriptor(name))
    return *row;
  std::string valid;
  for (const auto& n : descriptorNames())
    valid += (valid.empty() ? "" : ", ") + n;
  throw Error("unknown descriptor '" + name + "'; valid descriptors: " + valid);
}

std::vector<std::string> descriptorNames()
{
  std::vector<std::string> names;
  for (const auto& row : descriptorRegistry())
    names.emplace_back(row.name);
  return names;
}

}  // namespace openable
