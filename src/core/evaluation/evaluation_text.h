#pragma once
// Text helpers shared by the evaluation files (not part of the public API).

#include <fstream>
#include <string>

namespace openable
{
namespace detail
{
/// "RxC".
std::string shapeText(int rows, int cols);
/// A number as the metrics print it (up to 6 significant digits, no trailing zeros).
std::string numberText(double value);
/// Escapes quotes, backslashes and control characters for a JSON string.
std::string jsonEscape(const std::string& text);
/// An empty line or a `#` comment.
bool isCommentOrBlank(const std::string& line);
/// A `shape=RxC` comment: true with rows and cols set.
bool parseDeclaredShape(const std::string& line, int& rows, int& cols);
/// Opens a text file or throws Error naming `what` and the path.
std::ifstream openText(const std::string& path, const std::string& what);
}  // namespace detail
}  // namespace openable
