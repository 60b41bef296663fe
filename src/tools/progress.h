#pragma once

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>

namespace openable
{
/// Progress of a long run on stderr: items done, items per second and time left.
///
/// On a terminal it keeps one line up to date (redrawn with '\r' at most every `redraw` seconds); into a
/// file or pipe (a log, CI) it writes a plain line every `interval` seconds instead, so logs stay readable.
/// Quiet prints nothing. finish() prints the final line (and ends the terminal line). Not thread-safe:
/// one thread reports.
class Progress
{
public:
  /// Seconds since any fixed origin (steady, never going back).
  using Clock = std::function<double()>;

  struct Options
  {
    std::string label;            ///< what runs, e.g. the tool's name ("kitti_to_bag")
    std::string unit = "frames";  ///< what is counted
    size_t total = 0;             ///< 0 = unknown (no percentage, no time left)
    bool quiet = false;
    bool terminal = false;  ///< '\r' updates instead of plain lines
    double interval = 5.0;  ///< s between plain lines
    double redraw = 0.1;    ///< s between terminal redraws
  };

  /// Writes to `out` using `clock`: the form for tests (any stream, a fake clock).
  Progress(Options options, std::ostream& out, Clock clock);
  /// Writes to std::cerr on the steady clock; `terminal` is taken from isatty(stderr).
  Progress(const std::string& label, size_t total, bool quiet, const std::string& unit = "frames");
  ~Progress();

  /// `done` items are finished (monotonic; a smaller value is ignored).
  void update(size_t done);
  /// One more item finished.
  void step()
  {
    update(done_ + 1);
  }
  /// The final line; later calls do nothing. Called by the destructor when not called before.
  void finish();

  size_t done() const
  {
    return done_;
  }

private:
  void print(double now, bool final);

  Options options_;
  std::ostream& out_;
  Clock clock_;
  double start_;
  double last_print_;
  size_t done_ = 0;
  size_t last_length_ = 0;
  bool finished_ = false;
};

/// One progress line, e.g. "kitti_to_bag: 120/1101 frames (10%), 35.2 frames/s, 0:28 left"; without a total
/// "label: 120 frames, 35.2 frames/s"; no rate before any time has passed. Pure, for the tests.
std::string formatProgress(const std::string& label, const std::string& unit, size_t done, size_t total,
                           double elapsed_seconds);

/// A duration as "0:05", "12:34" or "1:02:03" (rounded to the second; negative counts as 0).
std::string formatDuration(double seconds);

}  // namespace openable
