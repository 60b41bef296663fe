// openable_offline's loop_closures.csv and decisions.csv: the writer, and the reader, strict so that a file
// from another version of the tool fails loudly instead of being scored wrongly.
#include "openable/detection/loop_csv.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "openable/error.h"

namespace openable
{
namespace
{
/// A number as both files write it: 6 significant digits, "nan" for what is not finite.
std::string formatFloat(float v)
{
  if (!std::isfinite(v))
    return "nan";
  std::ostringstream out;
  out << std::setprecision(6) << v;
  return out.str();
}

std::string trimmed(const std::string& text)
{
  const size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos)
  {
    return "";
  }
  return text.substr(first, text.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> splitFields(const std::string& line)
{
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');)
  {
    fields.push_back(trimmed(field));
  }
  // getline drops an empty last field ("a,b,"); keep it so the count is right.
  if (!line.empty() && trimmed(line).back() == ',')
  {
    fields.emplace_back();
  }
  return fields;
}

/// Column positions found by name in the header.
struct Columns
{
  int query = -1, match = -1, distance = -1, score = -1, status = -1, accepted = -1;
  size_t count = 0;
};

Columns findColumns(const std::string& header, const std::string& path)
{
  const std::vector<std::string> names = splitFields(header);
  Columns c;
  c.count = names.size();
  const auto find = [&](const std::string& name)
  {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  };
  c.query = find("query");
  c.match = find("match");
  c.distance = find("distance");
  c.score = find("score");
  c.status = find("status");
  c.accepted = find("accepted");
  for (const auto& [name, index] : {std::pair<const char*, int>{"query", c.query},
                                    {"match", c.match},
                                    {"distance", c.distance},
                                    {"score", c.score},
                                    {"status", c.status}})
  {
    if (index < 0)
    {
      throw Error("loop decisions: '" + path + "' has no '" + name + "' column (header '" + trimmed(header) +
                  "', expected query,match,distance,score,status[,accepted])");
    }
  }
  return c;
}

// FrameStatus is the one list of statuses: the words openable_offline writes come from toString.
// (Unconfirmed must stay the last enumerator, and they must count from 0.)
constexpr int kLastStatus = static_cast<int>(FrameStatus::Unconfirmed);

bool isStatusWord(const std::string& word)
{
  for (int s = 0; s <= kLastStatus; ++s)
  {
    if (word == toString(static_cast<FrameStatus>(s)))
    {
      return true;
    }
  }
  return false;
}

std::string statusWords()
{
  std::string list;
  for (int s = 0; s <= kLastStatus; ++s)
  {
    list += (s == 0 ? "" : ", ") + std::string(toString(static_cast<FrameStatus>(s)));
  }
  return list;
}

/// A non-negative frame index that is all of `text` (spaces around allowed).
bool parseFrame(const std::string& text, int& frame)
{
  std::istringstream in(text);
  long value = -1;
  std::string rest;
  if (!(in >> value) || (in >> rest) || value < 0 || value > 2147483647L)
    return false;
  frame = static_cast<int>(value);
  return true;
}

int parseIndex(const std::string& text, int minimum, const std::string& what, const std::string& where)
{
  errno = 0;
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || value < minimum || value > INT_MAX)
  {
    throw Error(where + ": " + what + " '" + text + "' is not an integer >= " + std::to_string(minimum));
  }
  return static_cast<int>(value);
}

double parseNumber(const std::string& text, const std::string& what, const std::string& where)
{
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0')
  {
    throw Error(where + ": " + what + " '" + text + "' is not a number (or nan)");
  }
  return value;
}

DecisionRow parseRow(const std::vector<std::string>& f, const Columns& c, const std::string& where)
{
  DecisionRow d;
  d.query = parseIndex(f[c.query], 0, "query", where);
  d.match = parseIndex(f[c.match], -1, "match", where);
  d.distance = parseNumber(f[c.distance], "distance", where);
  d.score = parseNumber(f[c.score], "score", where);
  d.status = f[c.status];
  if (!isStatusWord(d.status))
  {
    throw Error(where + ": unknown status '" + d.status + "' (known: " + statusWords() + ")");
  }
  if (c.accepted >= 0)
  {
    if (f[c.accepted] != "0" && f[c.accepted] != "1")
    {
      throw Error(where + ": accepted '" + f[c.accepted] + "' is not 0 or 1");
    }
    d.accepted = f[c.accepted] == "1";
  }
  if (d.published() && d.match < 0)
  {
    throw Error(where + ": a published loop closure without a match (match -1)");
  }
  return d;
}

}  // namespace

LoopCsvWriter::LoopCsvWriter(bool with_shift) : with_shift_(with_shift) {}

size_t LoopCsvWriter::add(const LoopCsvFrame& frame)
{
  frames_.push_back(frame);
  return frames_.size() - 1;
}

void LoopCsvWriter::setStatus(size_t row, FrameStatus status)
{
  if (row >= frames_.size())
    throw Error("loop decisions: no row " + std::to_string(row) + " to set (" + std::to_string(frames_.size()) +
                " rows)");
  frames_[row].status = status;
}

void LoopCsvWriter::setMatch(size_t row, long match)
{
  if (row >= frames_.size())
    throw Error("loop decisions: no row " + std::to_string(row) + " to set (" + std::to_string(frames_.size()) +
                " rows)");
  frames_[row].match = match;
}

void LoopCsvWriter::settlePending()
{
  for (LoopCsvFrame& f : frames_)
    if (f.status == FrameStatus::Pending)
      f.status = FrameStatus::Unconfirmed;
}

std::string LoopCsvWriter::loopClosures() const
{
  std::ostringstream out;
  out << "query,match,distance,score,status" << (with_shift_ ? ",direction,shift" : "")
      << ",query_session,match_session\n";
  for (const LoopCsvFrame& f : frames_)
  {
    if (f.status != FrameStatus::Published)
      continue;
    out << f.query << "," << f.match << "," << formatFloat(f.distance) << "," << formatFloat(f.score) << ",published";
    if (with_shift_)
      out << "," << f.direction << "," << f.shift;
    out << "," << f.query_session << "," << f.match_session << "\n";
  }
  return out.str();
}

std::string LoopCsvWriter::decisions() const
{
  std::ostringstream out;
  out << "query,match,distance,score,status,accepted,pace,inliers\n";
  for (const LoopCsvFrame& f : frames_)
  {
    const auto known = [&f](float v) { return formatFloat(f.has_candidates ? v : NAN); };
    out << f.query << "," << f.match << "," << known(f.distance) << "," << known(f.score) << "," << toString(f.status)
        << "," << (f.status == FrameStatus::Published ? 1 : 0) << "," << known(f.pace) << "," << f.inliers << "\n";
  }
  return out.str();
}

DecisionTable loadDecisionTable(const std::string& path)
{
  std::ifstream in(path);
  if (!in)
  {
    throw Error("loop decisions: cannot open '" + path + "' (missing or unreadable)");
  }
  DecisionTable table;
  table.path = path;
  std::string line;
  if (!std::getline(in, line) || trimmed(line).empty())
  {
    throw Error("loop decisions: '" + path + "' is empty (expected a header query,match,distance,score,status)");
  }
  const Columns columns = findColumns(line, path);
  table.per_frame = columns.accepted >= 0;
  for (int number = 2; std::getline(in, line); ++number)
  {
    if (trimmed(line).empty())
    {
      continue;
    }
    const std::string where = "loop decisions: '" + path + "' line " + std::to_string(number);
    const std::vector<std::string> fields = splitFields(line);
    if (fields.size() != columns.count)
    {
      throw Error(where + " has " + std::to_string(fields.size()) + " fields, the header " +
                  std::to_string(columns.count));
    }
    DecisionRow d = parseRow(fields, columns, where);
    d.line = number;
    if (!table.per_frame && !d.published())
    {
      throw Error(where + ": status '" + d.status +
                  "' in a loop closures file, which lists published loop closures only");
    }
    table.rows.push_back(std::move(d));
  }
  return table;
}

bool isLoopCsvHeader(const std::string& line)
{
  return line.rfind("query,match", 0) == 0;
}

bool readLoopCsvPair(const std::string& line, int& query, int& match)
{
  const size_t first = line.find(',');
  const size_t second = line.find(',', first == std::string::npos ? first : first + 1);
  return first != std::string::npos && parseFrame(line.substr(0, first), query) &&
         parseFrame(line.substr(first + 1, second == std::string::npos ? std::string::npos : second - first - 1),
                    match);
}

}  // namespace openable
