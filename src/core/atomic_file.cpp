#include "openable/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "openable/error.h"

namespace openable
{
void writeFileAtomically(const std::string& path, const std::string& bytes)
{
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw Error("cannot write '" + path + "': " + std::strerror(errno));
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out)
    {
      out.close();
      std::remove(temp.c_str());
      throw Error("cannot write '" + path + "' (disk full?)");
    }
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0)
  {
    const std::string reason = std::strerror(errno);
    std::remove(temp.c_str());
    throw Error("cannot move the new file into place at '" + path + "': " + reason);
  }
}

}  // namespace openable
