#pragma once

#include <string>

namespace openable
{
/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so readers see the
/// old file or the whole new one, never a partial one. Throws Error.
void writeFileAtomically(const std::string& path, const std::string& bytes);

}  // namespace openable
