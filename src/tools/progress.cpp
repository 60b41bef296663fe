#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <utility>

namespace openable
{
namespace
{
double steadySeconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

std::string formatDuration(double seconds)
{
  const long total = (std::isfinite(seconds) && seconds > 0.0) ? std::lround(seconds) : 0;
  char text[32];
  if (total >= 3600)
    std::snprintf(text, sizeof(text), "%ld:%02ld:%02ld", total / 3600, (total / 60) % 60, total % 60);
  else
    std::snprintf(text, sizeof(text), "%ld:%02ld", total / 60, total % 60);
  return text;
}

std::string formatProgress(const std::string& label, const std::string& unit, size_t done, size_t total,
                           double elapsed_seconds)
{
  std::string line = label.empty() ? "" : label + ": ";
  line += std::to_string(done);
  if (total > 0)
    line += "/" + std::to_string(total);
  line += " " + unit;
  if (total > 0)
    line += " (" + std::to_string(static_cast<int>(100.0 * static_cast<double>(std::min(done, total)) / total)) + "%)";
  // A rate needs measured time and work; before that it would be infinite or zero, i.e. noise.
  if (elapsed_seconds > 0.0 && done > 0)
  {
    const double rate = static_cast<double>(done) / elapsed_seconds;
    char text[48];
    std::snprintf(text, sizeof(text), ", %.1f %s/s", rate, unit.c_str());
    line += text;
    if (total > 0 && done < total)
      line += ", " + formatDuration(static_cast<double>(total - done) / rate) + " left";
  }
  return line;
}

Progress::Progress(Options options, std::ostream& out, Clock clock)
  : options_(std::move(options)), out_(out), clock_(std::move(clock))
{
  start_ = clock_();
  last_print_ = start_;
}

Progress::Progress(const std::string& label, size_t total, bool quiet, const std::string& unit)
  : Progress(Options{label, unit, total, quiet, ::isatty(STDERR_FILENO) == 1}, std::cerr, steadySeconds)
{
}

Progress::~Progress()
{
  finish();
}

void Progress::update(size_t done)
{
  if (done <= done_ || finished_)
    return;
  done_ = done;
  if (options_.quiet)
    return;
  const double now = clock_();
  const double wait = options_.terminal ? options_.redraw : options_.interval;
  if (now - last_print_ >= wait)
    print(now, false);
}

void Progress::finish()
{
  if (finished_)
    return;
  finished_ = true;
  if (!options_.quiet)
    print(clock_(), true);
}

void Progress::print(double now, bool final)
{
  last_print_ = now;
  const std::string line = formatProgress(options_.label, options_.unit, done_, options_.total, now - start_);
  if (!options_.terminal)
  {
    out_ << line << "\n";
    out_.flush();
    return;
  }
  // Blank out what is left of a longer previous line, then return to the line's start.
  const size_t pad = last_length_ > line.size() ? last_length_ - line.size() : 0;
  out_ << "\r" << line << std::string(pad, ' ');
  last_length_ = line.size();
  if (final)
    out_ << "\n";
  out_.flush();
}

}  // namespace openable
