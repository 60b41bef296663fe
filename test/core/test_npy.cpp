// .npy reader and writer: exact bytes, round trips, and every way a file can be wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "openable/error.h"
#include "openable/io/npy.h"

namespace fs = std::filesystem;

namespace
{
class NpyTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("openable_test_npy_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const
  {
    return (dir_ / name).string();
  }
  fs::path dir_;
};

std::string readBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes)
{
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

/// A .npy file made by hand: magic, version, header length (2 bytes for version 1, 4 otherwise), the dict
/// padded to 64 bytes, then `data`.
std::string handMadeNpy(const std::string& dict, const std::string& data, int version = 1)
{
  const size_t length_bytes = version == 1 ? 2 : 4;
  std::string header = dict;
  const size_t unpadded = 8 + length_bytes + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::string bytes("\x93NUMPY", 6);
  bytes.push_back(static_cast<char>(version));
  bytes.push_back('\0');
  for (size_t i = 0; i < length_bytes; ++i)
  {
    bytes.push_back(static_cast<char>((header.size() >> (8 * i)) & 0xff));
  }
  return bytes + header + data;
}

template <typename T>
std::string rawBytes(std::initializer_list<T> values)
{
  std::string bytes;
  for (T v : values)
  {
    bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  return bytes;
}

bool sameBits(const cv::Mat& a, const cv::Mat& b)
{
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

}  // namespace

TEST_F(NpyTest, WritesTheExactNumpyVersion1Layout)
{
  cv::Mat m = (cv::Mat_<float>(2, 3) << 1.0F, 2.0F, 3.0F, 4.0F, 5.0F, 6.5F);
  openable::writeNpy(path("m.npy"), m);
  const std::string bytes = readBytes(path("m.npy"));
  const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
  // 10 bytes of prefix + 59 of dict + 1 newline = 70, padded to 128: the data starts at byte 128.
  ASSERT_EQ(dict.size(), 59u);
  ASSERT_EQ(bytes.size(), 128u + 6 * 4);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 118);
  EXPECT_EQ(bytes[9], '\0');
  EXPECT_EQ(bytes.substr(10, dict.size()), dict);
  EXPECT_EQ(bytes.find_first_not_of(' ', 10 + dict.size()), 127u);
  EXPECT_EQ(bytes[127], '\n');
  EXPECT_EQ(bytes.substr(128), rawBytes<float>({1.0F, 2.0F, 3.0F, 4.0F, 5.0F, 6.5F}));
  EXPECT_EQ(bytes, handMadeNpy(dict, rawBytes<float>({1.0F, 2.0F, 3.0F, 4.0F, 5.0F, 6.5F})));
}

TEST_F(NpyTest, RoundTripKeepsEveryBitIncludingNanAndInfinity)
{
  cv::Mat m(37, 129, CV_32F);
  cv::randu(m, -1000.0, 1000.0);
  m.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
  m.at<float>(5, 7) = std::numeric_limits<float>::infinity();
  m.at<float>(36, 128) = -0.0F;
  openable::writeNpy(path("m.npy"), m);
  const cv::Mat back = openable::readNpy(path("m.npy"));
  EXPECT_TRUE(sameBits(m, back));
  EXPECT_TRUE(std::isnan(back.at<float>(0, 0)));
}

TEST_F(NpyTest, WritesARegionOfInterestRowByRow)
{
  cv::Mat big(10, 10, CV_32F);
  cv::randu(big, 0.0, 1.0);
  const cv::Mat roi = big(cv::Rect(2, 3, 4, 5));
  ASSERT_FALSE(roi.isContinuous());
  openable::writeNpy(path("roi.npy"), roi);
  EXPECT_TRUE(sameBits(roi.clone(), openable::readNpy(path("roi.npy"))));
}

TEST_F(NpyTest, WriteLeavesNoTemporaryFileAndReplacesTheOldOne)
{
  openable::writeNpy(path("m.npy"), cv::Mat(3, 3, CV_32F, cv::Scalar(1.0F)));
  openable::writeNpy(path("m.npy"), cv::Mat(2, 2, CV_32F, cv::Scalar(7.0F)));
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir_))
  {
    EXPECT_EQ(entry.path().filename(), "m.npy");
    ++files;
  }
  EXPECT_EQ(files, 1u);
  const cv::Mat back = openable::readNpy(path("m.npy"));
  EXPECT_EQ(back.size(), cv::Size(2, 2));
  EXPECT_EQ(back.at<float>(1, 1), 7.0F);
}

TEST_F(NpyTest, ReadsFloat64AsFloat32)
{
  writeBytes(path("d.npy"), handMadeNpy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }",
                                        rawBytes<double>({0.5, -2.25, 1e10, 3.0})));
  const cv::Mat m = openable::readNpy(path("d.npy"));
  ASSERT_EQ(m.type(), CV_32F);
  ASSERT_EQ(m.size(), cv::Size(2, 2));
  EXPECT_EQ(m.at<float>(0, 0), 0.5F);
  EXPECT_EQ(m.at<float>(0, 1), -2.25F);
  EXPECT_EQ(m.at<float>(1, 0), 1e10F);
  EXPECT_EQ(m.at<float>(1, 1), 3.0F);
}

TEST_F(NpyTest, ReadsVersion2HeadersAndKeyOrderAsNumpyMayWriteThem)
{
  // Key order and spacing differ from ours; version 2 has a 4-byte header length.
  writeBytes(path("v2.npy"), handMadeNpy("{'shape': (1, 3), 'fortran_order': False, 'descr': '<f4'}",
                                         rawBytes<float>({1.0F, 2.0F, 3.0F}), 2));
  const cv::Mat m = openable::readNpy(path("v2.npy"));
  ASSERT_EQ(m.size(), cv::Size(3, 1));
  EXPECT_EQ(m.at<float>(0, 2), 3.0F);
}

TEST_F(NpyTest, ReadsAnEmptyMatrix)
{
  writeBytes(path("e.npy"), handMadeNpy("{'descr': '<f4', 'fortran_order': False, 'shape': (0, 5), }", ""));
  const cv::Mat m = openable::readNpy(path("e.npy"));
  EXPECT_EQ(m.rows, 0);
  EXPECT_TRUE(m.empty());
}

/// Expects readNpy to throw an Error whose message contains `needle`.
void expectReadError(const std::string& file, const std::string& needle)
{
  try
  {
    openable::readNpy(file);
    ADD_FAILURE() << "no error for " << file;
  }
  catch (const openable::Error& e)
  {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST_F(NpyTest, RejectsEveryUnsupportedOrCorruptFileWithAReason)
{
  const std::string good = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }";
  const std::string data = rawBytes<float>({1.0F, 2.0F, 3.0F, 4.0F});
  expectReadError(path("missing.npy"), "cannot open");
  expectReadError(dir_.string(), "not a readable file");

  writeBytes(path("zero.npy"), "");
  expectReadError(path("zero.npy"), "not a .npy file");

  writeBytes(path("text.npy"), "threshold,precision,recall\n");
  expectReadError(path("text.npy"), "not a .npy file");

  writeBytes(path("fortran.npy"), handMadeNpy("{'descr': '<f4', 'fortran_order': True, 'shape': (2, 2), }", data));
  expectReadError(path("fortran.npy"), "Fortran order");

  writeBytes(path("int.npy"), handMadeNpy("{'descr': '<i4', 'fortran_order': False, 'shape': (2, 2), }", data));
  expectReadError(path("int.npy"), "'<i4'");

  writeBytes(path("big.npy"), handMadeNpy("{'descr': '>f4', 'fortran_order': False, 'shape': (2, 2), }", data));
  expectReadError(path("big.npy"), "'>f4'");

  writeBytes(path("1d.npy"), handMadeNpy("{'descr': '<f4', 'fortran_order': False, 'shape': (4,), }", data));
  expectReadError(path("1d.npy"), "1 dimensions");

  writeBytes(path("3d.npy"), handMadeNpy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 2), }", data));
  expectReadError(path("3d.npy"), "3 dimensions");

  writeBytes(path("short.npy"), handMadeNpy(good, data.substr(0, 12)));
  expectReadError(path("short.npy"), "truncated");

  writeBytes(path("long.npy"), handMadeNpy(good, data + "xx"));
  expectReadError(path("long.npy"), "trailing");

  writeBytes(path("cut_header.npy"), handMadeNpy(good, data).substr(0, 30));
  expectReadError(path("cut_header.npy"), "truncated inside its header");

  std::string version9 = handMadeNpy(good, data);
  version9[6] = 9;
  writeBytes(path("v9.npy"), version9);
  expectReadError(path("v9.npy"), "version 9");

  writeBytes(path("noshape.npy"), handMadeNpy("{'descr': '<f4', 'fortran_order': False}", data));
  expectReadError(path("noshape.npy"), "no 'shape'");

  // A corrupt shape asking for far more data than the file has is caught before allocating.
  writeBytes(path("huge.npy"),
             handMadeNpy("{'descr': '<f4', 'fortran_order': False, 'shape': (2000000000, 2000000000), }", data));
  expectReadError(path("huge.npy"), "truncated");
}

TEST_F(NpyTest, RejectsWritingAnythingButAFloatMatrix)
{
  EXPECT_THROW(openable::writeNpy(path("u8.npy"), cv::Mat(2, 2, CV_8U, cv::Scalar(1))), openable::Error);
  EXPECT_THROW(openable::writeNpy(path("f64.npy"), cv::Mat(2, 2, CV_64F, cv::Scalar(1))), openable::Error);
  EXPECT_THROW(openable::writeNpy(path("c3.npy"), cv::Mat(2, 2, CV_32FC3, cv::Scalar::all(1))), openable::Error);
  EXPECT_FALSE(fs::exists(path("u8.npy")));
  EXPECT_THROW(openable::writeNpy(path("no/such/folder/m.npy"), cv::Mat(2, 2, CV_32F, cv::Scalar(1))), openable::Error);
}
