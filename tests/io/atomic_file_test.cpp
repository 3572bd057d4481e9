#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace visvol {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

bool exists(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0;
}

mode_t type_of(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 ? (st.st_mode & S_IFMT) : 0;
}

// A character device to write at: a private copy of /dev/null where this test
// may make one (as root, where a regression would replace the real one), else
// /dev/null itself (which then cannot be replaced).
std::string device_node(const std::string& dir) {
  const std::string node = dir + "/null";
  return ::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0 ? node : "/dev/null";
}

std::string own_temp(const std::string& path) { return temporary_prefix(path) + std::to_string(::getpid()); }

// A pid that ran and has ended (and was reaped).
pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  ::waitpid(pid, nullptr, 0);
  return pid;
}

// A child that tests signals starts from their default actions: a shell
// that runs the suite in the background (SIGINT ignored) or nohup (SIGHUP)
// passes on "ignore", which install_output_cleanup_on_signals() keeps.
void default_signal_actions() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, SIG_DFL);
}

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/atomic_file_test_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  std::string dir_;
};

TEST_F(AtomicFile, WritesTheWholeFileAndLeavesNoTemporary) {
  const std::string out = dir_ + "/out.txt";
  write_text(out, "old");
  ASSERT_TRUE(write_file_atomically(out, "new content").ok());
  EXPECT_EQ(read_text(out), "new content");
  EXPECT_FALSE(exists(own_temp(out)));
}

TEST_F(AtomicFile, LinkPlantedAtTheTemporaryNameIsRefusedAndItsTargetUntouched) {
  const std::string victim = dir_ + "/victim", out = dir_ + "/out.vvp";
  write_text(victim, "precious");
  ASSERT_EQ(::symlink(victim.c_str(), own_temp(out).c_str()), 0);
  const Status st = write_file_atomically(out, "attack");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find(own_temp(out)), std::string::npos) << st.message();
  EXPECT_EQ(read_text(victim), "precious");
  EXPECT_EQ(type_of(own_temp(out)), S_IFLNK);  // not ours to remove
  EXPECT_FALSE(exists(out));
}

TEST_F(AtomicFile, LinkAtTheDestinationIsRefusedAndLeftAsItIs) {
  const std::string victim = dir_ + "/victim", out = dir_ + "/out.png";
  write_text(victim, "precious");
  ASSERT_EQ(::symlink(victim.c_str(), out.c_str()), 0);
  const Status st = write_file_atomically(out, "attack");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find(out + ": is a symbolic link, not a regular file"), std::string::npos) << st.message();
  EXPECT_EQ(type_of(out), S_IFLNK);
  EXPECT_EQ(read_text(victim), "precious");
  EXPECT_FALSE(exists(own_temp(out)));
}

TEST_F(AtomicFile, DeviceFifoAndDirectoryDestinationsAreRefusedAndLeftAsTheyAre) {
  const std::string fifo = dir_ + "/fifo", folder = dir_ + "/folder";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  ASSERT_EQ(::mkdir(folder.c_str(), 0755), 0);
  const std::pair<std::string, mode_t> cases[] = {{device_node(dir_), S_IFCHR}, {fifo, S_IFIFO}, {folder, S_IFDIR}};
  for (const auto& [path, type] : cases) {
    const Status st = write_file_atomically(path, "x");
    ASSERT_FALSE(st.ok()) << path;
    EXPECT_EQ(st.code(), Errc::invalid_argument) << path;
    EXPECT_NE(st.message().find(path + ": is a"), std::string::npos) << st.message();
    EXPECT_EQ(type_of(path), type) << path;
    EXPECT_FALSE(exists(own_temp(path))) << path;
  }
  // and through OutputFile directly, in the library form too
  EXPECT_FALSE(OutputFile::create_for_library(fifo).ok());
  EXPECT_EQ(type_of(fifo), S_IFIFO);
}

TEST_F(AtomicFile, AnOutputNotCommittedLeavesTheOldFileAndNoTemporary) {
  const std::string out = dir_ + "/out.bin";
  write_text(out, "old");
  {
    Result<OutputFile> f = OutputFile::create(out);
    ASSERT_TRUE(f.ok()) << f.status().message();
    ASSERT_TRUE(f->write("half", 4).ok());
    EXPECT_TRUE(exists(own_temp(out)));
  }
  EXPECT_EQ(read_text(out), "old");
  EXPECT_FALSE(exists(own_temp(out)));
}

TEST_F(AtomicFile, ALibraryWritesInsideAPrivateDirectoryThenItIsRenamed) {
  const std::string out = dir_ + "/dem.tif";
  Result<OutputFile> f = OutputFile::create_for_library(out);
  ASSERT_TRUE(f.ok()) << f.status().message();
  EXPECT_EQ(f->fd(), -1);
  EXPECT_EQ(type_of(own_temp(out)), S_IFDIR);
  struct stat st {};
  ASSERT_EQ(::stat(own_temp(out).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  write_text(f->write_path(), "by path");
  write_text(own_temp(out) + "/side.aux.xml", "a side file");
  ASSERT_TRUE(f->commit().ok());
  EXPECT_EQ(read_text(out), "by path");
  EXPECT_FALSE(exists(own_temp(out)));
}

TEST_F(AtomicFile, ASharedFileIsOpenInsideAPrivateDirectoryThenRenamedOrRemoved) {
  const std::string out = dir_ + "/pack.vvp";
  write_text(out, "old");
  for (const bool keep : {false, true}) {
    {
      Result<OutputFile> f = OutputFile::create_shared(out);
      ASSERT_TRUE(f.ok()) << f.status().message();
      ASSERT_GE(f->fd(), 0);
      EXPECT_EQ(type_of(own_temp(out)), S_IFDIR);
      EXPECT_EQ(f->write_path(), own_temp(out) + "/pack.vvp");
      EXPECT_EQ(type_of(f->write_path()), S_IFREG);
      struct stat st {};
      ASSERT_EQ(::stat(own_temp(out).c_str(), &st), 0);
      EXPECT_EQ(st.st_mode & 0777, 0700u);
      ASSERT_TRUE(f->write_at("shared", 6, 0).ok());
      if (keep) {
        ASSERT_TRUE(f->commit().ok());
      }
    }  // dropped, committed or not
    EXPECT_EQ(read_text(out), keep ? "shared" : "old");
    EXPECT_FALSE(exists(own_temp(out)));
  }
}

TEST_F(AtomicFile, StaleTemporariesOfDeadProcessesAreSweptThoseOfLiveOnesKept) {
  const std::string out = dir_ + "/sf.vvp", victim = dir_ + "/victim";
  const std::string dead = temporary_prefix(out) + std::to_string(dead_pid());
  const std::string dead_dir = temporary_prefix(out) + std::to_string(dead_pid());
  const std::string dead_link = temporary_prefix(out) + std::to_string(dead_pid());
  const std::string live = temporary_prefix(out) + std::to_string(::getppid());
  const std::string other = temporary_prefix(dir_ + "/other.vvp") + std::to_string(dead_pid());
  // before the host was in the name: swept like this host's
  const std::string legacy = out + ".tmp." + std::to_string(dead_pid());
  // another host's on a shared file system: its pid means nothing here
  const std::string other_host =
      out + ".tmp.x" + temporary_prefix(out).substr(out.size() + 5) + std::to_string(dead_pid());
  write_text(dead, "600 MB of a killed build");
  ASSERT_EQ(::mkdir(dead_dir.c_str(), 0700), 0);
  write_text(dead_dir + "/sf.vvp", "half a GeoTIFF");
  write_text(victim, "precious");
  ASSERT_EQ(::symlink(victim.c_str(), dead_link.c_str()), 0);
  write_text(live, "a build still running");
  write_text(other, "another output's");
  write_text(legacy, "an older version's");
  write_text(other_host, "a build running on another host");
  ASSERT_TRUE(write_file_atomically(out, "pack").ok());
  EXPECT_FALSE(exists(legacy));
  EXPECT_TRUE(exists(other_host));
  EXPECT_FALSE(exists(dead));
  EXPECT_FALSE(exists(dead_dir));
  EXPECT_EQ(type_of(dead_link), S_IFLNK);  // never created by us: left
  EXPECT_EQ(read_text(victim), "precious");
  EXPECT_TRUE(exists(live));
  EXPECT_TRUE(exists(other));
  EXPECT_EQ(read_text(out), "pack");
}

TEST_F(AtomicFile, AStaleTemporaryWithThisProcessesPidIsSweptUnlessLive) {
  const std::string out = dir_ + "/a.csv";
  write_text(own_temp(out), "from an earlier process with the same pid");
  Result<OutputFile> f = OutputFile::create(out);
  ASSERT_TRUE(f.ok()) << f.status().message();
  // a second writer of the same output while the first is live is refused
  const Result<OutputFile> g = OutputFile::create(out);
  EXPECT_FALSE(g.ok());
  ASSERT_TRUE(f->write("1", 1).ok());
  ASSERT_TRUE(f->commit().ok());
  EXPECT_EQ(read_text(out), "1");
}

// Writing past the file size limit fails with EFBIG like a full disk with
// ENOSPC: the operation failed (Errc::output), and no temporary is left.
TEST_F(AtomicFile, AFailedWriteIsAnOutputErrorAndRemovesTheTemporary) {
  const std::string out = dir_ + "/big.bin";
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    const Status st = write_file_atomically(out, std::string(1 << 20, 'x'));
    const bool ok = !st.ok() && st.code() == Errc::output && st.message().find(out) != std::string::npos &&
                    !exists(own_temp(out)) && !exists(out);
    ::_exit(ok ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// A set of files replaces the earlier set whole, or leaves it as it was: the
// disk filling at the third file (a file size limit here) changes none of them
// (a plan's four files had been half new, half gone).
TEST_F(AtomicFile, ASetOfFilesIsReplacedWholeOrNotAtAll) {
  const std::vector<std::string> names = {dir_ + "/p.csv", dir_ + "/p.kml", dir_ + "/p.plan"};
  for (const std::string& n : names) write_text(n, "earlier");
  // the earlier set's file the new one lacks: removed only with the new set
  const std::string stale = dir_ + "/p.geojson";
  write_text(stale, "earlier");
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    std::vector<std::string> written, removed;
    const Status st =
        write_files_atomically({{names[0], "new csv"}, {names[1], "new kml"}, {names[2], std::string(1 << 20, 'x')}},
                               {stale}, written, removed);
    bool ok = !st.ok() && st.code() == Errc::output && written.empty() && removed.empty();
    for (const std::string& n : names) ok = ok && read_text(n) == "earlier" && !exists(own_temp(n));
    ok = ok && read_text(stale) == "earlier";
    ::_exit(ok ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);

  std::vector<std::string> written, removed;
  ASSERT_TRUE(
      write_files_atomically({{names[0], "a"}, {names[1], "b"}, {names[2], "c"}}, {stale}, written, removed).ok());
  EXPECT_EQ(written, names);
  EXPECT_EQ(removed, std::vector<std::string>{stale});
  EXPECT_FALSE(exists(stale));
  EXPECT_EQ(read_text(names[0]) + read_text(names[1]) + read_text(names[2]), "abc");
  // a bad name among them (a directory where a file goes): nothing changes
  std::filesystem::remove(names[1]);
  std::filesystem::create_directory(names[1]);
  written.clear();
  removed.clear();
  const Status refused =
      write_files_atomically({{names[0], "x"}, {names[1], "y"}, {names[2], "z"}}, {}, written, removed);
  EXPECT_EQ(refused.code(), Errc::invalid_argument) << refused.message();
  EXPECT_TRUE(written.empty());
  EXPECT_EQ(read_text(names[0]) + read_text(names[2]), "ac");
  EXPECT_FALSE(exists(own_temp(names[0])));
}

// A signal that lands while a set is renamed into place waits for the last
// rename, then ends the process as it would have (its default action): the
// new set is whole, the earlier set's stale file gone, and stderr says the
// set was written whole first. Without the wait, the signal raised between
// the stale file's removal and the first rename would leave the earlier
// files and no stale one: a set that is neither.
TEST_F(AtomicFile, ASignalDuringTheRenamesWaitsForTheWholeSet) {
  const std::vector<std::string> names = {dir_ + "/s.csv", dir_ + "/s.kml", dir_ + "/s.plan"};
  const std::string stale = dir_ + "/s.geojson";
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    for (const std::string& n : names) write_text(n, "earlier");
    write_text(stale, "earlier");
    const std::string err = dir_ + "/stderr.txt";
    const pid_t pid = ::fork();
    if (pid == 0) {
      const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);  // as a shell's 2> does
      if (fd < 0 || ::dup2(fd, 2) != 2) ::_exit(3);
      default_signal_actions();
      install_output_cleanup_on_signals();
      static int raised = 0;
      raised = sig;
      g_inside_rename_window_for_tests = [] { std::raise(raised); };
      std::vector<std::string> written, removed;
      (void)write_files_atomically({{names[0], "new"}, {names[1], "new"}, {names[2], "new"}}, {stale}, written,
                                   removed);
      ::_exit(4);  // the signal, raised again after the renames, ends the process first
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig << ", exit " << WEXITSTATUS(status);
    EXPECT_EQ(WTERMSIG(status), sig);
    for (const std::string& n : names) {
      EXPECT_EQ(read_text(n), "new") << n << ", signal " << sig;
      EXPECT_FALSE(exists(temporary_prefix(n) + std::to_string(pid))) << n;
    }
    EXPECT_FALSE(exists(stale)) << "signal " << sig;
    const std::string said = read_text(err);
    EXPECT_NE(said.find("interrupted (signal " + std::to_string(sig) +
                        ") as the outputs were renamed into place: written whole first"),
              std::string::npos)
        << said;
  }
}

// A child writing an output is killed by `sig`; returns the temporary's name.
std::string killed_while_writing(const std::string& out, int sig, bool library, int& wait_status) {
  int ready[2];
  if (::pipe(ready) != 0) return "";
  const pid_t pid = ::fork();
  if (pid == 0) {
    default_signal_actions();
    install_output_cleanup_on_signals();
    Result<OutputFile> f = library ? OutputFile::create_for_library(out) : OutputFile::create(out);
    if (!f.ok()) ::_exit(3);
    if (library) {
      write_text(f->write_path(), "partial");
      // and a side file of the library's own, as GDAL writes (.aux.xml)
      write_text(f->write_path() + ".aux.xml", "<PAMDataset/>");
    } else if (!f->write("partial", 7).ok()) {
      ::_exit(4);
    }
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(5);
    while (true) ::pause();
  }
  ::close(ready[1]);
  char byte = 0;
  const bool told = ::read(ready[0], &byte, 1) == 1;
  ::close(ready[0]);
  const std::string temp = temporary_prefix(out) + std::to_string(pid);
  const bool was_there = exists(temp);
  ::kill(pid, sig);
  ::waitpid(pid, &wait_status, 0);
  return told && was_there ? temp : "(the child never wrote its temporary)";
}

// SIGHUP too: a console's terminal closing ends its writes the same way.
TEST_F(AtomicFile, SigintSigtermAndSighupRemoveTheTemporariesThenEndTheProcessBySignal) {
  for (const bool library : {false, true}) {
    for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
      const std::string out = dir_ + "/killed.vvp";
      int status = 0;
      const std::string temp = killed_while_writing(out, sig, library, status);
      ASSERT_EQ(temp.find(out), 0u) << temp;
      EXPECT_FALSE(exists(temp)) << temp;
      EXPECT_FALSE(exists(out));
      ASSERT_TRUE(WIFSIGNALED(status)) << "library " << library << " signal " << sig;
      EXPECT_EQ(WTERMSIG(status), sig);
    }
  }
}

}  // namespace
}  // namespace visvol
