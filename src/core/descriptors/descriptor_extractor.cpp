// What every DescriptorExtractor shares: the refusals of the form it lacks. The extractors are in this
// folder, one file each, and built through the registry (descriptor_registry.cpp).
#include "openable/descriptors/descriptor_extractor.h"

#include "openable/error.h"

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

}  // namespace openable
