// NumPy .npy reader and writer for the 2-D float matrices the toolbox exchanges with Python.
// Format reference: numpy/lib/format.py (magic, version, little-endian header length, Python dict
// literal padded so the data starts on a 64-byte boundary).
#include "openable/io/atomic_file.h"
#include "openable/io/npy.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "openable/error.h"
#include "openable/io/image_source.h"

namespace openable
{
namespace
{
const char kMagic[] = "\x93NUMPY";
const size_t kMagicSize = 6;
// Data must start on a multiple of this many bytes (numpy >= 1.14 writes 64 for memory mapping).
const size_t kAlignment = 64;

bool isLittleEndianHost()
{
  const uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// Headers are a few hundred bytes; a bigger one is corrupt or not worth supporting.
const size_t kMaxHeadBytes = 1 << 20;

/// Opens `path` and returns its size and its first bytes (up to kMaxHeadBytes): the header is parsed from
/// these, and the data is then read straight into the matrix (no second copy of a large file).
std::ifstream openWithHead(const std::string& path, uint64_t& file_size, std::string& head)
{
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in)
  {
    throw Error("npy: cannot open '" + path + "' for reading (missing or unreadable)");
  }
  const std::streamoff end = in.tellg();
  if (end < 0 || std::filesystem::is_directory(path))
  {
    throw Error("npy: '" + path + "' is not a readable file");
  }
  file_size = static_cast<uint64_t>(end);
  head.resize(static_cast<size_t>(std::min<uint64_t>(file_size, kMaxHeadBytes)));
  in.seekg(0);
  if (!in.read(&head[0], static_cast<std::streamsize>(head.size())))
  {
    throw Error("npy: cannot read '" + path + "'");
  }
  return in;
}

uint32_t readLittleEndian(const std::string& bytes, size_t offset, size_t width)
{
  uint32_t value = 0;
  for (size_t i = 0; i < width; ++i)
  {
    value |= static_cast<uint32_t>(static_cast<unsigned char>(bytes[offset + i])) << (8 * i);
  }
  return value;
}

/// The value text of `key` in the header dict, e.g. "'<f4'" or "(3, 4)"; throws when absent.
std::string dictValue(const std::string& header, const std::string& key, const std::string& path)
{
  const std::string quoted_single = "'" + key + "'";
  const std::string quoted_double = "\"" + key + "\"";
  size_t pos = header.find(quoted_single);
  size_t key_size = quoted_single.size();
  if (pos == std::string::npos)
  {
    pos = header.find(quoted_double);
    key_size = quoted_double.size();
  }
  if (pos == std::string::npos)
  {
    throw Error("npy: '" + path + "' header has no '" + key + "' entry: " + header);
  }
  size_t colon = header.find(':', pos + key_size);
  if (colon == std::string::npos)
  {
    throw Error("npy: '" + path + "' header is malformed near '" + key + "': " + header);
  }
  size_t begin = header.find_first_not_of(" \t", colon + 1);
  if (begin == std::string::npos)
  {
    throw Error("npy: '" + path + "' header is malformed near '" + key + "': " + header);
  }
  // A tuple value contains commas, so it ends at its closing parenthesis, anything else at a comma.
  size_t end = header[begin] == '(' ? header.find(')', begin) : header.find_first_of(",}", begin);
  if (end == std::string::npos)
  {
    throw Error("npy: '" + path + "' header is malformed near '" + key + "': " + header);
  }
  if (header[begin] == '(')
  {
    ++end;
  }
  std::string value = header.substr(begin, end - begin);
  value.erase(value.find_last_not_of(" \t") + 1);
  return value;
}

std::vector<uint64_t> parseShape(const std::string& tuple, const std::string& path)
{
  if (tuple.size() < 2 || tuple.front() != '(' || tuple.back() != ')')
  {
    throw Error("npy: '" + path + "' has a malformed shape " + tuple);
  }
  std::vector<uint64_t> dims;
  std::stringstream items(tuple.substr(1, tuple.size() - 2));
  std::string item;
  while (std::getline(items, item, ','))
  {
    const size_t first = item.find_first_not_of(" \t");
    if (first == std::string::npos)
    {
      continue;  // the trailing comma of a 1-tuple "(5,)"
    }
    item = item.substr(first, item.find_last_not_of(" \t") - first + 1);
    if (item.find_first_not_of("0123456789") != std::string::npos || item.size() > 18)
    {
      throw Error("npy: '" + path + "' has a malformed shape " + tuple);
    }
    dims.push_back(std::stoull(item));
  }
  return dims;
}

struct NpyHeader
{
  std::string descr;
  bool fortran_order = false;
  std::vector<uint64_t> shape;
  size_t data_offset = 0;
};

NpyHeader parseHeader(const std::string& bytes, const std::string& path)
{
  if (bytes.size() < kMagicSize + 4 || bytes.compare(0, kMagicSize, kMagic, kMagicSize) != 0)
  {
    throw Error("npy: '" + path + "' is not a .npy file (no \\x93NUMPY magic)");
  }
  const int major = static_cast<unsigned char>(bytes[6]);
  // Version 1 stores the header length in 2 bytes; versions 2 and 3 in 4 (3 only changes the encoding).
  if (major < 1 || major > 3)
  {
    throw Error("npy: '" + path + "' has unsupported format version " + std::to_string(major) +
                " (expected 1, 2 or 3)");
  }
  const size_t width = major == 1 ? 2 : 4;
  if (bytes.size() < 8 + width)
  {
    throw Error("npy: '" + path + "' is truncated inside its header");
  }
  const size_t header_size = readLittleEndian(bytes, 8, width);
  NpyHeader header;
  header.data_offset = 8 + width + header_size;
  if (bytes.size() < header.data_offset && bytes.size() == kMaxHeadBytes)
  {
    throw Error("npy: '" + path + "' declares a header of " + std::to_string(header_size) +
                " bytes; more than 1 MiB is not supported");
  }
  if (bytes.size() < header.data_offset)
  {
    throw Error("npy: '" + path + "' is truncated inside its header (" + std::to_string(bytes.size()) +
                " bytes, header ends at " + std::to_string(header.data_offset) + ")");
  }
  const std::string dict = bytes.substr(8 + width, header_size);
  header.descr = dictValue(dict, "descr", path);
  header.fortran_order = dictValue(dict, "fortran_order", path) == "True";
  header.shape = parseShape(dictValue(dict, "shape", path), path);
  return header;
}

/// C order, two dimensions, each below 2^31 (what a cv::Mat can hold).
void checkLayout(const NpyHeader& header, const std::string& path)
{
  if (header.fortran_order)
  {
    throw Error("npy: '" + path + "' is in Fortran order; save it in C order (numpy.ascontiguousarray)");
  }
  if (header.shape.size() != 2)
  {
    throw Error("npy: '" + path + "' has " + std::to_string(header.shape.size()) +
                " dimensions; a 2-D matrix is expected");
  }
  if (header.shape[0] > static_cast<uint64_t>(INT32_MAX) || header.shape[1] > static_cast<uint64_t>(INT32_MAX))
  {
    throw Error("npy: '" + path + "' has a shape too large for a matrix");
  }
}

void checkSupported(const NpyHeader& header, const std::string& path)
{
  if (header.descr != "'<f4'" && header.descr != "'<f8'")
  {
    throw Error("npy: '" + path + "' has dtype " + header.descr +
                "; only little-endian float32 '<f4' and float64 '<f8' are supported");
  }
  checkLayout(header, path);
}

/// The data of a checked header as a rows x `raw_cols` matrix of `type` (`item` bytes per cell). The file
/// must hold exactly that many bytes, checked before allocating: a corrupt shape cannot ask for terabytes.
cv::Mat readData(std::ifstream& in, const NpyHeader& header, uint64_t file_size, size_t item, const std::string& path,
                 int type, int raw_cols)
{
  const int rows = static_cast<int>(header.shape[0]);
  const int cols = static_cast<int>(header.shape[1]);
  // Dims are < 2^31 each, so the product of three factors (<= 2^67) is formed in two checked steps.
  const uint64_t available = file_size - header.data_offset;
  const uint64_t cells = header.shape[0] * header.shape[1];
  const bool overflows = cells > UINT64_MAX / item;
  const uint64_t expected = overflows ? UINT64_MAX : cells * item;
  if (available != expected)
  {
    throw Error("npy: '" + path + "' holds " + std::to_string(available) + " data bytes but its shape (" +
                std::to_string(rows) + ", " + std::to_string(cols) + ") needs " +
                (overflows ? std::string("more than 2^64") : std::to_string(expected)) +
                (available < expected ? " (truncated)" : " (trailing garbage)"));
  }
  cv::Mat raw(rows, raw_cols, type);
  in.seekg(static_cast<std::streamoff>(header.data_offset));
  if (expected > 0 && !in.read(reinterpret_cast<char*>(raw.data), static_cast<std::streamsize>(expected)))
  {
    throw Error("npy: cannot read the data of '" + path + "'");
  }
  return raw;
}

/// Item size of the dtypes readNpyNonZero takes (bool, integers, floats; little-endian or single byte),
/// 0 for any other. '<' and '|' are both fine for one-byte types: numpy writes '|'.
size_t nonZeroItemSize(const std::string& descr)
{
  if (descr.size() != 5 || descr.front() != '\'' || descr.back() != '\'')
  {
    return 0;
  }
  const char order = descr[1], kind = descr[2], width = descr[3];
  const bool one_byte = width == '1' && (order == '|' || order == '<') && (kind == 'b' || kind == 'u' || kind == 'i');
  const bool integer = order == '<' && (kind == 'u' || kind == 'i') && (width == '2' || width == '4' || width == '8');
  const bool floating = order == '<' && kind == 'f' && (width == '4' || width == '8');
  return (one_byte || integer || floating) ? static_cast<size_t>(width - '0') : 0;
}

std::string makeHeader(int rows, int cols)
{
  std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
                     std::to_string(cols) + "), }";
  // Pad with spaces and end with a newline so magic + version + length + dict is a multiple of 64.
  const size_t prefix = kMagicSize + 2 + 2;
  const size_t unpadded = prefix + dict.size() + 1;
  dict.append((kAlignment - unpadded % kAlignment) % kAlignment, ' ');
  dict.push_back('\n');
  if (dict.size() > UINT16_MAX)
  {
    throw Error("npy: header too long");
  }
  std::string header(kMagic, kMagicSize);
  header.push_back('\x01');
  header.push_back('\x00');
  header.push_back(static_cast<char>(dict.size() & 0xff));
  header.push_back(static_cast<char>((dict.size() >> 8) & 0xff));
  return header + dict;
}

}  // namespace

void writeNpy(const std::string& path, const cv::Mat& matrix)
{
  if (matrix.type() != CV_32FC1 || matrix.dims != 2)
  {
    throw Error("npy: cannot write '" + path + "': a 2-D single-channel CV_32F matrix is expected (got type " +
                std::to_string(matrix.type()) + ", " + std::to_string(matrix.dims) + " dimensions)");
  }
  if (!isLittleEndianHost())
  {
    throw Error("npy: writing '<f4' on a big-endian host is not supported");
  }
  std::string bytes = makeHeader(matrix.rows, matrix.cols);
  const size_t row_bytes = static_cast<size_t>(matrix.cols) * sizeof(float);
  bytes.reserve(bytes.size() + row_bytes * static_cast<size_t>(matrix.rows));
  // Row by row because a ROI view of a bigger matrix is not continuous.
  for (int r = 0; r < matrix.rows; ++r)
  {
    bytes.append(reinterpret_cast<const char*>(matrix.ptr<float>(r)), row_bytes);
  }
  writeFileAtomically(path, bytes);
}

cv::Mat readNpy(const std::string& path)
{
  if (!isLittleEndianHost())
  {
    throw Error("npy: reading little-endian data on a big-endian host is not supported");
  }
  uint64_t file_size = 0;
  std::string head;
  std::ifstream in = openWithHead(path, file_size, head);
  const NpyHeader header = parseHeader(head, path);
  checkSupported(header, path);
  const size_t item = header.descr == "'<f4'" ? 4 : 8;
  const cv::Mat raw =
      readData(in, header, file_size, item, path, item == 4 ? CV_32F : CV_64F, static_cast<int>(header.shape[1]));
  if (item == 4)
  {
    return raw;
  }
  cv::Mat matrix;
  raw.convertTo(matrix, CV_32F);
  return matrix;
}

cv::Mat readNpyNonZero(const std::string& path)
{
  if (!isLittleEndianHost())
  {
    throw Error("npy: reading little-endian data on a big-endian host is not supported");
  }
  uint64_t file_size = 0;
  std::string head;
  std::ifstream in = openWithHead(path, file_size, head);
  const NpyHeader header = parseHeader(head, path);
  const size_t item = nonZeroItemSize(header.descr);
  if (item == 0)
  {
    throw Error("npy: '" + path + "' has dtype " + header.descr +
                "; expected bool, a little-endian integer or float32/float64");
  }
  checkLayout(header, path);
  const int rows = static_cast<int>(header.shape[0]);
  const int cols = static_cast<int>(header.shape[1]);
  if (static_cast<uint64_t>(cols) * item > static_cast<uint64_t>(INT32_MAX))
  {
    throw Error("npy: '" + path + "' has rows too long for a matrix");
  }
  const cv::Mat raw = readData(in, header, file_size, item, path, CV_8U, static_cast<int>(cols * item));
  const bool floating = header.descr[2] == 'f';
  cv::Mat non_zero(rows, cols, CV_8U);
  for (int r = 0; r < rows; ++r)
  {
    const unsigned char* bytes = raw.ptr<unsigned char>(r);
    unsigned char* out = non_zero.ptr<unsigned char>(r);
    for (int c = 0; c < cols; ++c, bytes += item)
    {
      bool set = false;
      if (floating && item == 4)
      {
        float value = 0.0F;
        std::memcpy(&value, bytes, 4);
        set = value != 0.0F;  // -0.0 is zero, NaN is not (numpy.nonzero agrees)
      }
      else if (floating)
      {
        double value = 0.0;
        std::memcpy(&value, bytes, 8);
        set = value != 0.0;
      }
      else
      {
        // An integer or bool is zero exactly when all its bytes are, whatever the byte order.
        set = std::any_of(bytes, bytes + item, [](unsigned char b) { return b != 0; });
      }
      out[c] = set ? 255 : 0;
    }
  }
  return non_zero;
}

}  // namespace openable
