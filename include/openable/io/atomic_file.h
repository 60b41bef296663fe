#pragma once

#include <string>

namespace openable
{
/// Writes `bytes` to `path` through a temporary file in the same folder (`<path>.tmp.<pid>`), fsynced, then
/// renamed over `path` and the folder fsynced, so readers (and a machine that loses power) see the old file
/// or the whole new one, never a partial one. Temporary files of `path` left by dead processes (a kill -9)
/// are removed first. Throws Error ("... (disk full?)" when a write fails), leaving `path` untouched.
void writeFileAtomically(const std::string& path, const std::string& bytes);

/// fsync of a file or a folder (a folder: its entries, so a rename in it is durable). Throws Error.
void syncPath(const std::string& path);

/// Moves the finished file `temp` over `path` (fsync of `temp`, rename, fsync of the folder). Throws Error
/// and removes `temp` when it cannot.
void publishFile(const std::string& temp, const std::string& path);

/// `<path>.tmp.<pid>` of this process, after removing those of dead processes.
std::string temporaryPath(const std::string& path);

/// Whether a process `pid` exists (a leftover of a process that does not is stale).
bool processAlive(long pid);

/// The number after the last '.' of `name` when `name` is `prefix` followed by digits only, else -1.
long pidSuffix(const std::string& name, const std::string& prefix);

/// Test hook: called with a step name at every point of a file write or an output publish where a kill
/// must leave a consistent state (after each write, fsync and rename). Null (the default) does nothing.
using OutputStepHook = void (*)(const char* step);
void setOutputStepHook(OutputStepHook hook);
void outputStep(const char* step);

}  // namespace openable
