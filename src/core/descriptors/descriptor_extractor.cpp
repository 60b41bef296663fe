// What every DescriptorExtractor shares (the refusals of the form it lacks), the names, and the factory
// that builds an extractor by name. The extractors themselves are in src/core/descriptors/.
#include "openable/descriptors/descriptor_extractor.h"

#include <algorithm>

#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "openable/descriptors/ldb.h"

namespace openable
{
void DescriptorExtractor::describeBinary(const Patch&, uint64_t*) const
{
  throw Error(name() + " is a vector descriptor; it has no binary form");
}

void DescriptorExtractor::describeFloat(const Patch&, float*) const
{
  throw Error(name() + " is a binary descriptor; it has no float form");
}

const std::vector<std::string>& descriptorNames()
{
  static const std::vector<std::string> names = {"LDB",   "D-LDB", "BRIEF", "BRISK", "ORB",
                                                 "FREAK", "SIFT",  "SURF",  "HOG",   "HOG-B"};
  return names;
}

namespace
{
std::unique_ptr<DescriptorExtractor> createByName(const Config& config)
{
  const std::string& name = config.descriptor;
  if (name == "LDB")
    return std::make_unique<LdbExtractor>();
  // A new extractor: `if (name == "X") return std::make_unique<XExtractor>(...);` and X in descriptorNames().
  if (name == "D-LDB")
    return std::make_unique<DldbExtractor>();
  // The others scale their pattern or window to patch_size (their constructors reject too small a patch).
  const int p = config.patch_size;
  if (name == "BRIEF")
    return std::make_unique<BriefExtractor>(p);
  if (name == "FREAK")
    return std::make_unique<FreakExtractor>(p);
  if (name == "SURF")
    return std::make_unique<SurfExtractor>(p);
  if (name == "ORB")
    return std::make_unique<OrbExtractor>(p);
  if (name == "BRISK")
    return std::make_unique<BriskExtractor>(p);
  if (name == "SIFT")
    return std::make_unique<SiftExtractor>(p);
  if (name == "HOG")
    return std::make_unique<HogExtractor>(p);
  if (name == "HOG-B")
    return std::make_unique<HogBinaryExtractor>(p);
  (void)config;
  return nullptr;
}
}  // namespace

std::unique_ptr<DescriptorExtractor> createDescriptorExtractor(const Config& config)
{
  const auto& names = descriptorNames();
  if (std::find(names.begin(), names.end(), config.descriptor) == names.end())
  {
    std::string valid;
    for (const auto& n : names)
      valid += (valid.empty() ? "" : ", ") + n;
    throw Error("unknown descriptor '" + config.descriptor + "'; valid descriptors: " + valid);
  }
  if (config.descriptor == "D-LDB" && config.camera_type != "stereo")
    throw Error("descriptor D-LDB describes disparity and needs camera_type stereo (got " + config.camera_type + ")");
  auto extractor = createByName(config);
  if (!extractor)
    throw Error("descriptor '" + config.descriptor + "' is not available in this build");
  if (config.patch_size < extractor->minPatchSize())
    throw Error("patch_size " + std::to_string(config.patch_size) + " is too small for " + extractor->name() +
                "; expected at least " + std::to_string(extractor->minPatchSize()));
  return extractor;
}

}  // namespace openable
