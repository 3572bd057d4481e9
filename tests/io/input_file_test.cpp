#include "io/input_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>

namespace visvol {
namespace {

class InputFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/input_file_test_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  std::string dir_;
};

TEST_F(InputFileTest, ReadsARegularFileAndOneThroughASymlink) {
  const std::string file = dir_ + "/a.txt", link = dir_ + "/link.txt";
  std::ofstream(file) << "hello";
  ASSERT_EQ(::symlink(file.c_str(), link.c_str()), 0);
  for (const std::string& path : {file, link}) {
    const Result<std::string> text = read_input_file(path, 100);
    ASSERT_TRUE(text.ok()) << text.status().message();
    EXPECT_EQ(*text, "hello");
  }
  EXPECT_TRUE(check_input_file(link).ok());
}

// open() of a FIFO without a writer would wait for ever: refused at once.
TEST_F(InputFileTest, AFifoIsRefusedAtOnceNamingIt) {
  const std::string fifo = dir_ + "/pack.vvp";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const auto start = std::chrono::steady_clock::now();
  const Result<InputFile> f = InputFile::open(fifo);
  const Status checked = check_input_file(fifo);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  ASSERT_FALSE(f.ok());
  EXPECT_EQ(f.status().code(), Errc::invalid_argument);
  EXPECT_EQ(f.status().message(), fifo + ": is a FIFO, not a regular file");
  EXPECT_EQ(checked.message(), f.status().message());
}

TEST_F(InputFileTest, DevicesAndDirectoriesAreRefusedMissingFilesNamed) {
  EXPECT_EQ(check_input_file("/dev/zero").message(), "/dev/zero: is a character device, not a regular file");
  EXPECT_EQ(check_input_file(dir_).message(), dir_ + ": is a directory, not a regular file");
  const Status missing = check_input_file(dir_ + "/none.tif");
  EXPECT_EQ(missing.code(), Errc::io);
  EXPECT_NE(missing.message().find(dir_ + "/none.tif: No such file"), std::string::npos) << missing.message();
}

TEST_F(InputFileTest, AFileLargerThanTheLimitIsRefused) {
  const std::string file = dir_ + "/big.txt";
  std::ofstream(file) << std::string(101, 'x');
  const Result<std::string> text = read_input_file(file, 100);
  ASSERT_FALSE(text.ok());
  EXPECT_EQ(text.status().code(), Errc::invalid_argument);
  EXPECT_NE(text.status().message().find("larger than"), std::string::npos);
  EXPECT_TRUE(read_input_file(file, 101).ok());
}

// GDAL opens DEM.prj and the like by name: a FIFO there would block it.
TEST_F(InputFileTest, AFifoBesideAnInputWithTheSameStemIsRefused) {
  const std::string dem = dir_ + "/dem.asc";
  std::ofstream(dem) << "ncols 1";
  std::ofstream(dir_ + "/dem.hdr") << "";
  std::ofstream(dir_ + "/other.prj") << "";
  ASSERT_EQ(::mkfifo((dir_ + "/other.aux").c_str(), 0644), 0);
  EXPECT_TRUE(check_side_files(dem).ok());
  ASSERT_EQ(::mkfifo((dir_ + "/DEM.PRJ").c_str(), 0644), 0);
  const Status st = check_side_files(dem);
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find(dir_ + "/DEM.PRJ: is a FIFO, not a regular file"), std::string::npos) << st.message();
}

// The descriptor is blocking again: reads of a regular file behave as usual.
TEST_F(InputFileTest, ReadAtReadsExactlyOrNamesTheShortFile) {
  const std::string file = dir_ + "/bytes.bin";
  std::ofstream(file) << "0123456789";
  Result<InputFile> f = InputFile::open(file);
  ASSERT_TRUE(f.ok());
  char out[4] = {};
  ASSERT_TRUE(f->read_at(out, 4, 3).ok());
  EXPECT_EQ(std::string(out, 4), "3456");
  ASSERT_TRUE(f->read_at(out, 4, 6).ok());  // up to the last byte
  EXPECT_EQ(std::string(out, 4), "6789");
  const Status past = f->read_at(out, 4, 8);
  ASSERT_FALSE(past.ok());
  EXPECT_EQ(past.code(), Errc::io);
  EXPECT_NE(past.message().find(file), std::string::npos) << past.message();
  EXPECT_NE(past.message().find("ended at byte 10, 12 expected"), std::string::npos) << past.message();
  // cut short after it was opened: the same error, not a fault
  ASSERT_EQ(::truncate(file.c_str(), 2), 0);
  EXPECT_EQ(f->read_at(out, 4, 0).code(), Errc::io);
}

TEST_F(InputFileTest, TheDescriptorIsLeftBlocking) {
  const std::string file = dir_ + "/a.txt";
  std::ofstream(file) << "x";
  const Result<InputFile> f = InputFile::open(file);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(::fcntl(f->fd(), F_GETFL) & O_NONBLOCK, 0);
  EXPECT_EQ(f->size_bytes(), 1u);
}

}  // namespace
}  // namespace visvol
