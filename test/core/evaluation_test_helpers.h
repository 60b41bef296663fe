// What the evaluation tests share: the data folders, a temporary folder per test, expectError.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "openable/error.h"

namespace evaluation_test
{
inline const float kNan = std::numeric_limits<float>::quiet_NaN();
inline const std::string kData = OPENABLE_SOURCE_DIR "/../shared/data";
inline const std::string kKitti = kData + "/kitti";

class TempDir
{
public:
  TempDir()
  {
    path_ = std::filesystem::temp_directory_path() / ("openable_test_evaluation_" +
                                         std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir()
  {
    std::filesystem::remove_all(path_);
  }
  std::string file(const std::string& name, const std::string& text) const
  {
    const std::string p = (path_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string path(const std::string& name) const
  {
    return (path_ / name).string();
  }

private:
  std::filesystem::path path_;
};

/// Expects `call` to throw an Error whose message contains `needle`.
template <typename Call>
void expectError(Call call, const std::string& needle)
{
  try
  {
    call();
    ADD_FAILURE() << "no error, expected one containing '" << needle << "'";
  }
  catch (const openable::Error& e)
  {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace evaluation_test
