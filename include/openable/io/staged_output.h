#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace openable
{
/// The output set of one tool run, published all-or-nothing (README, "Output sets").
///
/// A tool's set is the files it writes into its output folder `dir`, under the name `set` (the tool's name).
/// The files are written into a staging folder, each fsynced; publish() writes the set's manifest
/// (`.openable_set.<set>`, one file name a line), fsyncs the staging folder and makes the new set visible:
/// - when `dir` is missing, empty, or holds only this set's earlier files (what its manifest lists), the
///   staging folder is the sibling `<dir>.openable_staging.<pid>` and is exchanged with `dir` in one atomic
///   rename (Linux renameat2 RENAME_EXCHANGE): a kill -9 at any point leaves `dir` with the earlier set or
///   the new one, and the earlier set (now in the staging name) is removed;
/// - when `dir` also holds files this set does not own (the user's, another tool's), or is a symbolic link
///   or the working folder, the set lives in a generation folder `<dir>/.openable_data.<set>.<n>.<pid>`, and
///   each of its files in `dir` is a symbolic link `<name> -> .openable_current.<set>/<name>` through the
///   set's current link `<dir>/.openable_current.<set>`, which names the generation (as Kubernetes' atomic
///   writer does). publish() moves the staging folder `<dir>/.openable_staging.<set>.<pid>` to a new
///   generation, makes the links the new set adds (they point at nothing until the switch: the name stays
///   absent), then switches the current link in one atomic rename: a reader sees the earlier set or the new
///   one at every instant. The earlier set's links the new one lacks and the earlier generation are removed
///   after. An earlier set of plain files (from an owned folder) is first hard-linked into a generation of
///   its own and each file replaced by its link, the same bytes before and after.
/// Files of `dir` that the set does not own are never touched.
///
/// The constructor first cleans up after dead runs (processes no longer running) on `dir`: it removes their
/// staging folders, `*.tmp.<pid>` files, generation folders that are not current and links that point at
/// nothing the current set has.
class StagedOutput
{
public:
  /// Creates the parent folders of `dir` when missing; throws Error when the set cannot be staged (now, not
  /// after minutes of work).
  StagedOutput(const std::string& dir, const std::string& set);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// Where to write the output file `name` (no folder part) before publish().
  std::string path(const std::string& name);
  /// Publishes every file asked for with path() as the new set. Throws Error (the earlier set then stays).
  void publish();

  /// What a dead run left on `dir` cleaned up, as the constructor does (for a reader that wants a settled
  /// folder without writing one).
  static void recover(const std::string& dir);
  /// The manifest's file name of `set`.
  static std::string manifestName(const std::string& set);

private:
  bool ownsFolder() const;
  void publishByExchange();
  void publishShared();
  void linkEarlierSet(const std::vector<std::string>& earlier);

  std::filesystem::path dir_, staging_;
  std::string set_;
  std::vector<std::string> names_;
  bool exchange_ = false;
  bool created_ = false;
  bool published_ = false;
};

}  // namespace openable
