// Hostile outputs and inputs through the visvol command: links and device
// nodes at output paths, FIFOs as inputs, killed builds, stale temporaries and
// full disks. Every command runs under `timeout` so a hang fails the test.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "cli_runner.hpp"
#include "io/atomic_file.hpp"

namespace {

using visvol::temporary_prefix;
using visvol::test::kCrop;
using visvol::test::kDem;
using visvol::test::kSmallPackOptions;
using visvol::test::Outcome;
using visvol::test::slurp;

// Shell words under a 60 s limit (exit 124 or 137 when they hang).
Outcome run_limited(const std::string& shell_words) {
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(getpid());
  const std::string out = dir + "/outputs_out_" + tag, err = dir + "/outputs_err_" + tag;
  const std::string cmd = "timeout -k 5 60 " + shell_words + " </dev/null >" + out + " 2>" + err;
  const int rc = std::system(cmd.c_str());
  Outcome r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

// visvol with `args`, likewise.
Outcome visvol(const std::string& args) { return run_limited(std::string(VISVOL_BIN) + " " + args); }

mode_t type_of(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 ? (st.st_mode & S_IFMT) : 0;
}

bool exists(const std::string& path) { return type_of(path) != 0; }

// A character device to write at: a private copy of /dev/null where this test
// may make one (as root, where a regression would replace the real one), else
// /dev/null itself (which then cannot be replaced).
std::string device_node(const std::string& dir) {
  const std::string node = dir + "/null";
  return ::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0 ? node : "/dev/null";
}

pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  ::waitpid(pid, nullptr, 0);
  return pid;
}

class Outputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/outputs_cli_test_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    dir_ = new std::string(tmpl);
    pack_ = new std::string(*dir_ + "/small.vvp");
    const Outcome r = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + *pack_);
    ASSERT_EQ(r.status, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::system(("rm -rf " + *dir_).c_str());
    delete pack_;
    delete dir_;
  }
  void SetUp() override { std::ofstream(victim()) << "precious"; }
  static std::string victim() { return *dir_ + "/victim"; }

  // Each writing command with its output path last.
  static std::vector<std::string> writers() {
    return {"build " + kDem + " " + kSmallPackOptions + " -o ",
            "viewshed " + kDem + " " + kCrop + " --observer 550500 4182100 -o ",
            "export " + *pack_ + " --layer height -o ", "render " + *pack_ + " --size 64x48 -o "};
  }

  static std::string* dir_;
  static std::string* pack_;
};
std::string* Outputs::dir_ = nullptr;
std::string* Outputs::pack_ = nullptr;

// The temporary's name is predictable (NAME.tmp.<host>.<pid>): the shell that
// execs visvol plants a link there first. The build refuses it; the target is intact.
TEST_F(Outputs, ALinkPlantedAtTheTemporaryNameIsRefused) {
  const std::string out = *dir_ + "/planted.vvp";
  const Outcome r = run_limited("sh -c 'ln -s " + victim() + " " + temporary_prefix(out) + "$$ && exec " + VISVOL_BIN +
                                " build " + kDem + " " + kSmallPackOptions + " -o " + out + "'");
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("already exists (a symbolic link); not following or replacing it"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(victim()), "precious");
  EXPECT_FALSE(exists(out));
  std::system(("rm -f " + out + ".tmp.*").c_str());
}

// An output that is the command's own input (by another name, a hard link)
// would be overwritten while read: export -o its pack replaced the pack by a
// VTI, build -o its DEM the DEM by a pack. Refused, the input unchanged.
TEST_F(Outputs, AnOutputThatIsTheCommandsOwnInputIsRefused) {
  const std::string dem = *dir_ + "/dem_copy.tif", pack = *dir_ + "/pack_copy.vvp";
  ASSERT_EQ(std::system(("cp " + kDem + " " + dem + " && cp " + *pack_ + " " + pack).c_str()), 0);
  const std::string linked = *dir_ + "/pack_link.vvp";
  ASSERT_EQ(::link(pack.c_str(), linked.c_str()), 0);
  const std::string dem_bytes = slurp(dem), pack_bytes = slurp(pack);
  const std::pair<std::string, std::string> cases[] = {
      {"export " + pack + " --layer height --format vti -o " + linked, "-o " + linked + " is the pack " + pack},
      {"render " + pack + " --size 64x48 -o " + *dir_ + "/./pack_copy.vvp", "is the pack " + pack},
      {"build " + dem + " " + kSmallPackOptions + " -o " + dem, "-o " + dem + " is the DEM " + dem},
      {"viewshed " + dem + " " + kCrop + " --observer 550500 4182100 -o " + dem, "is the DEM " + dem}};
  for (const auto& [args, expected] : cases) {
    const Outcome r = visvol(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("the command would overwrite its own input"), std::string::npos) << r.err;
  }
  EXPECT_EQ(slurp(dem), dem_bytes);
  EXPECT_EQ(slurp(pack), pack_bytes);
}

TEST_F(Outputs, ALinkADeviceOrAFifoAtTheOutputIsRefusedAndLeftAsItIs) {
  const std::string link = *dir_ + "/link.out", fifo = *dir_ + "/fifo.out";
  ASSERT_EQ(::symlink(victim().c_str(), link.c_str()), 0);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::pair<std::string, mode_t> targets[] = {{link, S_IFLNK}, {fifo, S_IFIFO}, {device_node(*dir_), S_IFCHR}};
  for (const std::string& w : writers()) {
    for (const auto& [path, type] : targets) {
      const Outcome r = visvol(w + path);
      EXPECT_EQ(r.status, 2) << w << path << "\n" << r.err;
      EXPECT_NE(r.err.find(path + ": is a"), std::string::npos) << w << path << "\n" << r.err;
      EXPECT_NE(r.err.find("not a regular file; refusing to replace it"), std::string::npos) << r.err;
      EXPECT_EQ(type_of(path), type) << w << path;
    }
  }
  EXPECT_EQ(slurp(victim()), "precious");
  std::remove(link.c_str());
  std::remove(fifo.c_str());
}

// A bad output is refused before the work, not after it: plan writes none of
// its four files when one of them is a link (it wrote the CSV first before),
// where the same plan with a good -o succeeds.
TEST_F(Outputs, ABadOutputIsRefusedBeforeAnyWorkAndNothingIsWritten) {
  const std::string plan = "plan " + *pack_ +
                           " --from 550300 4181900 200 --to 550800 4182400 200 --objective hide"
                           " --init straight --segments 16 --max-seconds 1 -o ";
  const std::string base = *dir_ + "/early";
  ASSERT_EQ(::symlink(victim().c_str(), (base + ".kml").c_str()), 0);
  const Outcome r = visvol(plan + base);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("-o: " + base + ".kml: is a symbolic link"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(base + ".csv"));
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(slurp(victim()), "precious");
  std::remove((base + ".kml").c_str());
  const Outcome good = visvol(plan + base);
  EXPECT_NE(good.status, 2) << good.err;  // 0, or 1 naming a requirement unmet
  EXPECT_TRUE(exists(base + ".csv")) << good.err;
  for (const char* extension : {".csv", ".kml", ".plan", ".geojson"}) std::remove((base + extension).c_str());

  // the other writers: a directory that does not exist, named before anything is printed
  const std::string nowhere = *dir_ + "/no_such_directory/out";
  for (const std::string& w : writers()) {
    if (w.rfind("build", 0) == 0) continue;  // the pack writer opens its output first already
    const Outcome b = visvol(w + nowhere);
    EXPECT_EQ(b.status, 2) << w << "\n" << b.err;
    EXPECT_NE(b.err.find("-o: " + nowhere + ": directory " + *dir_ + "/no_such_directory"), std::string::npos)
        << w << "\n"
        << b.err;
    EXPECT_EQ(b.out, "") << w;
  }
}

// open() of a FIFO for reading waits for a writer: every input refuses it at once.
TEST_F(Outputs, AFifoAsInputExitsTwoAtOnce) {
  const std::string fifo = *dir_ + "/input.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::string ends = " --from 550100 4181700 300 --to 551000 4182600 300 --objective hide";
  for (const std::string& args :
       {"info " + fifo, "verify " + fifo, "sample " + fifo, "build " + fifo + " -o " + *dir_ + "/x.vvp",
        "viewshed " + fifo + " --observer 1 2 -o " + *dir_ + "/x.tif", "check " + *pack_ + " " + fifo,
        "plan " + *pack_ + ends + " --init " + fifo + " -o " + *dir_ + "/x.txt",
        "render " + *pack_ + " --path " + fifo + " -o " + *dir_ + "/x.png",
        "render " + *pack_ + " --transfer " + fifo + " -o " + *dir_ + "/x.png"}) {
    const auto start = std::chrono::steady_clock::now();
    const Outcome r = visvol(args);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30)) << args;
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(fifo + ": is a FIFO, not a regular file"), std::string::npos) << args << "\n" << r.err;
  }
  EXPECT_EQ(type_of(fifo), S_IFIFO);
  std::remove(fifo.c_str());
  // GDAL opens a grid's .prj by name: a FIFO there is refused too
  const std::string grid = *dir_ + "/grid.asc", prj = *dir_ + "/grid.prj";
  std::ofstream(grid) << "ncols 3\nnrows 3\nxllcorner 500000\nyllcorner 4000000\ncellsize 30\n1 2 3\n4 5 6\n7 8 9\n";
  ASSERT_EQ(::mkfifo(prj.c_str(), 0644), 0);
  const Outcome r = visvol("info " + grid);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find(prj + ": is a FIFO, not a regular file"), std::string::npos) << r.err;
  std::remove(prj.c_str());
  std::remove(grid.c_str());
}

// A killed build leaves NAME.tmp.<host>.<pid>; the next write of that output
// removes it (the process is gone), and keeps one of a process that still
// runs, and another host's (a shared file system: its pids mean nothing here).
TEST_F(Outputs, StaleTemporariesOfDeadProcessesAreSweptByTheNextWrite) {
  const std::string out = *dir_ + "/swept.vvp";
  const std::string stale = temporary_prefix(out) + std::to_string(dead_pid());
  const std::string live = temporary_prefix(out) + std::to_string(getpid());
  // "<host>.tmp.x<this host>.<pid>": a name this host never gives
  const std::string other_host =
      out + ".tmp.x" + temporary_prefix(out).substr(out.size() + 5) + std::to_string(dead_pid());
  std::ofstream(stale) << "what a killed build left";
  std::ofstream(live) << "a build still running";
  std::ofstream(other_host) << "a build running on another host";
  const Outcome r = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(exists(stale));
  EXPECT_TRUE(exists(live));
  EXPECT_TRUE(exists(other_host));
  std::remove(live.c_str());
  std::remove(other_host.c_str());
  std::remove(out.c_str());
}

// SIGTERM (or Ctrl-C) during a build removes its temporary.
TEST_F(Outputs, AKilledBuildLeavesNoTemporary) {
  const std::string out = *dir_ + "/killed.vvp";
  for (const int sig : {SIGTERM, SIGINT}) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      const std::string args = "build " + kDem + " --fill-nodata -o " + out;
      std::freopen("/dev/null", "w", stderr);
      ::execl("/bin/sh", "sh", "-c", ("exec " + std::string(VISVOL_BIN) + " " + args).c_str(),
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const std::string temp = temporary_prefix(out) + std::to_string(pid);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!exists(temp) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    const bool seen = exists(temp);
    ::kill(pid, sig);
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (!seen && WIFEXITED(status)) GTEST_SKIP() << "the build ended before its temporary was seen";
    ASSERT_TRUE(seen);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_FALSE(exists(temp));
    EXPECT_FALSE(exists(out));
  }
}

// A write that fails for want of space is a failed operation (exit 1), not
// bad input, and leaves neither the output nor a temporary. The file size
// limit gives EFBIG without privileges (SIGXFSZ ignored, as a shell's trap
// passes on); a small tmpfs gives ENOSPC where this test may mount one.
TEST_F(Outputs, AFullDiskExitsOneAndLeavesNothing) {
  const std::string out = *dir_ + "/limited.out";
  const std::pair<std::string, int> limited[] = {{writers()[0], 64}, {writers()[1], 1}};  // 512-byte blocks
  for (const auto& [w, blocks] : limited) {
    const Outcome r = run_limited("sh -c \"trap '' XFSZ; ulimit -f " + std::to_string(blocks) + "; exec " + VISVOL_BIN +
                                  " " + w + out + "\"");
    EXPECT_EQ(r.status, 1) << w << "\n" << r.err;
    EXPECT_NE(r.err.find(out + ": "), std::string::npos) << r.err;
    EXPECT_NE(std::system(("ls " + out + "* >/dev/null 2>&1").c_str()), 0) << w << " left a file";
  }

  const std::string mnt = *dir_ + "/tiny";
  ASSERT_EQ(::mkdir(mnt.c_str(), 0755), 0);
  if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=16k") != 0) {
    GTEST_SKIP() << "cannot mount a tmpfs here (not root): ENOSPC not tried";
  }
  // a pack and a 100 KiB volume do not fit in 16 KiB
  for (const std::string& w : {writers()[0], "export " + *pack_ + " --layer visibility -o "}) {
    const Outcome r = visvol(w + mnt + "/out");
    EXPECT_EQ(r.status, 1) << w << "\n" << r.err;
    EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << w << "\n" << r.err;
    EXPECT_NE(std::system(("ls -A " + mnt + " | grep -q .").c_str()), 0) << w << " left a file";
  }
  ::umount(mnt.c_str());
}

}  // namespace
