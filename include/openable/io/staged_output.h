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
///   or the working folder, only this set's files
///   are replaced, through a journal: the staging folder `<dir>/.openable_staging.<set>.<pid>` is renamed to
///   `<dir>/.openable_commit.<set>.<pid>` (the commit point, after which the new set is the one that
///   counts), then its files are moved into `dir`, the earlier set's files that the new one lacks removed,
///   and the manifest moved last. A kill after the commit is completed (rolled forward) by the next run on
///   `dir`; a kill before it leaves the earlier set and a staging folder that the next run removes.
/// Files of `dir` that the set does not own are never touched.
///
/// The constructor first cleans up after dead runs (processes no longer running) on `dir`: it removes their
/// staging folders and `*.tmp.<pid>` files and completes their committed journals.
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
  void publishByJournal();

  std::filesystem::path dir_, staging_;
  std::string set_;
  std::vector<std::string> names_;
  bool exchange_ = false;
  bool created_ = false;
  bool published_ = false;
};

}  // namespace openable
