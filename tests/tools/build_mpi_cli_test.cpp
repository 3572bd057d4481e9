// visvol-build-mpi under mpirun on this machine (2 and 3 ranks, shared memory
// and loopback only): the pack of `visvol build`, byte for byte; a killed rank
// or bad input leaves no pack; bad input exits 2 naming it.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <dirent.h>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../storage/pack_bytes.hpp"
#include "cli_runner.hpp"

namespace visvol {
namespace {

using storage::testing::read_bytes;
using storage::testing::without_build_time;
using test::Outcome;

// Shared memory between the ranks, loopback for mpirun's own traffic.
const std::string kMpirun = std::string(VISVOL_MPIEXEC) +
                            " --oversubscribe --allow-run-as-root --mca btl self,vader --mca oob_tcp_if_include lo";

Outcome build_mpi(int ranks, const std::string& args) {
  return test::run_command(kMpirun + " -np " + std::to_string(ranks) + " " + VISVOL_BUILD_MPI_BIN + " " + args);
}

std::string temp(const std::string& stem) {
  return ::testing::TempDir() + "/" + stem + "_" + std::to_string(getpid()) + ".vvp";
}

// Files next to `path` whose names start with its own (temporaries).
std::vector<std::string> leftovers(const std::string& path) {
  const std::string dir = path.substr(0, path.rfind('/')), stem = path.substr(path.rfind('/') + 1);
  std::vector<std::string> found;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* e = ::readdir(d)) {
      const std::string name = e->d_name;
      if (name.rfind(stem + ".tmp", 0) == 0) found.push_back(name);
    }
    ::closedir(d);
  }
  return found;
}

// The last column of the per-rank table: MiB of sums each rank sent.
std::vector<double> sums_sent_mib(const std::string& out) {
  std::vector<double> mib;
  std::istringstream lines(out.substr(std::min(out.size(), out.find("\nrank  threads"))));
  std::string line;
  std::getline(lines, line);  // the blank line before the header
  std::getline(lines, line);  // the header
  while (std::getline(lines, line) && line.rfind("exchanged", 0) != 0) {
    const std::size_t last = line.find_last_of(' ');
    if (last != std::string::npos) mib.push_back(std::atof(line.c_str() + last + 1));
  }
  return mib;
}

TEST(BuildMpi, TwoAndThreeRanksWriteTheSingleProcessPackByteForByte) {
  const std::string one = temp("mpi_one"), many = temp("mpi_many");
  // 40 x 40 posts: level 0 has 3 rows of bricks and 1 of height tiles, so
  // some ranks build no height tiles and rows straddle the ranks' bands.
  const std::string options = test::kDem + " " + test::kSmallPackOptions;
  const Outcome single = test::visvol("build " + options + " -o " + one);
  ASSERT_EQ(single.status, 0) << single.err;
  // split by observers (the default: the sums over rows of other bands sent
  // between the ranks) and by rows
  for (const auto& [ranks, split] :
       {std::pair<int, std::string>{2, ""}, {3, " --split observers"}, {2, " --split rows"}}) {
    const Outcome r = build_mpi(ranks, options + split + " -o " + many);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("on " + std::to_string(ranks) + " ranks"), std::string::npos) << r.out;
    // the per-rank table: every rank sent sums split by observers, none by rows
    const std::vector<double> sent = sums_sent_mib(r.out);
    ASSERT_EQ(sent.size(), static_cast<std::size_t>(ranks)) << r.out;
    for (const double mib : sent) EXPECT_EQ(mib > 0, split != " --split rows") << r.out;
    EXPECT_TRUE(without_build_time(many) == without_build_time(one)) << ranks << " ranks" << split;
    const Outcome verified = test::visvol("verify " + many);
    EXPECT_EQ(verified.status, 0) << verified.err;
    std::remove(many.c_str());
  }
  std::remove(one.c_str());
}

pid_t parent_of(pid_t pid) {
  const std::string stat = test::slurp("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t close = stat.rfind(')');  // the name may hold spaces
  int ppid = -1;
  if (close != std::string::npos) std::sscanf(stat.c_str() + close + 1, " %*c %d", &ppid);
  return static_cast<pid_t>(ppid);
}

bool descends_from(pid_t pid, pid_t ancestor) {
  for (int depth = 0; pid > 1 && depth < 16; ++depth, pid = parent_of(pid)) {
    if (pid == ancestor) return true;
  }
  return false;
}

// The pid of rank `rank` of the visvol-build-mpi job started as `job` (from
// the environment mpirun gives its ranks), or -1.
pid_t rank_pid(pid_t job, int rank) {
  const std::string want = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  DIR* proc = ::opendir("/proc");
  pid_t found = -1;
  while (const dirent* e = proc ? ::readdir(proc) : nullptr) {
    const pid_t pid = static_cast<pid_t>(std::atoi(e->d_name));
    if (pid <= 0 || !descends_from(pid, job)) continue;
    const std::string cmdline = test::slurp("/proc/" + std::to_string(pid) + "/cmdline");
    if (cmdline.find("visvol-build-mpi") == std::string::npos) continue;
    const std::string env = test::slurp("/proc/" + std::to_string(pid) + "/environ");
    std::size_t at = 0;
    for (std::size_t end; (end = env.find('\0', at)) != std::string::npos; at = end + 1) {
      if (env.compare(at, end - at, want) == 0) found = pid;
    }
  }
  if (proc) ::closedir(proc);
  return found;
}

// A job in its own process group, ended with the group whatever the test's outcome.
struct Job {
  pid_t pid = -1;
  explicit Job(const std::string& cmd) {
    pid = ::fork();
    if (pid == 0) {
      ::setpgid(0, 0);
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::setpgid(pid, pid);
  }
  ~Job() {
    if (pid <= 0) return;
    ::kill(-pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
  }
  int wait() {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, 0);
    pid = -1;
    return done > 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
};

std::string joined(const std::vector<std::string>& names) {
  std::string all;
  for (const std::string& n : names) all += n + " ";
  return all;
}

TEST(BuildMpi, TheGivenPlanningMarginReachesEveryRank) {
  // a range wider than half the 40-post crop: only --planning-margin leaves bounds
  const std::string one = temp("mpi_margin_one"), many = temp("mpi_margin_many");
  const std::string options = test::kDem + " " + test::kCrop +
                              " --levels 16 --range 24 --lod 1 --tff-offset 60 --tff-levels 6 --planning-margin 150";
  const Outcome single = test::visvol("build " + options + " -o " + one);
  ASSERT_EQ(single.status, 0) << single.err;
  const Outcome r = build_mpi(2, options + " -o " + many);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(without_build_time(many) == without_build_time(one));
  std::remove(one.c_str());
  std::remove(many.c_str());
}

TEST(BuildMpi, AKilledRankFailsTheJobAndLeavesTheOldPack) {
  const std::string path = temp("mpi_killed");
  const Outcome first = test::visvol("build " + test::kDem + " " + test::kSmallPackOptions + " -o " + path);
  ASSERT_EQ(first.status, 0) << first.err;
  const std::vector<char> before = read_bytes(path);
  // the whole DEM at 64 levels: a few seconds a rank
  const std::string cmd = kMpirun + " -np 2 " + VISVOL_BUILD_MPI_BIN + " " + test::kDem +
                          " --fill-nodata --range 24 --levels 64 --lod 2 --threads 1 -o " + path;
  const std::string err = ::testing::TempDir() + "/mpi_killed_err_" + std::to_string(getpid());
  Job job(cmd + " >/dev/null 2>" + err);
  // kill rank 1 once the build's temporary exists (the tiles are being written)
  pid_t victim = -1;
  for (int i = 0; i < 400 && victim < 0; ++i) {
    if (!leftovers(path).empty()) victim = rank_pid(job.pid, 1);
    if (victim < 0) ::usleep(25 * 1000);
  }
  const std::string said_before = victim > 0 ? "" : test::slurp(err);
  if (victim < 0) std::remove(err.c_str());
  ASSERT_GT(victim, 0) << "rank 1 never started: " << said_before;
  ::kill(victim, SIGKILL);
  const int status = job.wait();
  const std::string said = test::slurp(err);
  std::remove(err.c_str());
  if (status == 0 && said.find("signal 9") == std::string::npos) {
    GTEST_SKIP() << "the build ended before rank 1 was killed";  // a machine fast enough to finish first
  }
  EXPECT_NE(status, 0);
  EXPECT_NE(said.find("rank 1"), std::string::npos) << said;
  EXPECT_NE(said.find("signal 9"), std::string::npos) << said;
  EXPECT_TRUE(read_bytes(path) == before);  // the old pack, untouched
  for (int i = 0; i < 100 && !leftovers(path).empty(); ++i) ::usleep(20 * 1000);
  EXPECT_TRUE(leftovers(path).empty()) << joined(leftovers(path));
  std::remove(path.c_str());
}

TEST(BuildMpi, BadInputExitsTwoNamingItAndWritesNothing) {
  const std::string path = temp("mpi_bad");
  Outcome r = build_mpi(2, test::kDem + " " + test::kSmallPackOptions + " --range -3 -o " + path);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("range"), std::string::npos) << r.err;
  r = build_mpi(2, "/nonexistent/dem.tif -o " + path);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/nonexistent/dem.tif"), std::string::npos) << r.err;
  r = build_mpi(2, test::kDem + " " + test::kSmallPackOptions);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--output"), std::string::npos) << r.err;
  r = build_mpi(2, test::kDem + " " + test::kSmallPackOptions + " --split tiles -o " + path);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--split"), std::string::npos) << r.err;
  EXPECT_NE(::access(path.c_str(), F_OK), 0);
  // an output that is a link: refused, its target untouched
  const std::string target = temp("mpi_link_target");
  std::ofstream(target) << "keep";
  ASSERT_EQ(::symlink(target.c_str(), path.c_str()), 0);
  r = build_mpi(2, test::kDem + " " + test::kSmallPackOptions + " -o " + path);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(test::slurp(target), "keep");
  EXPECT_TRUE(leftovers(path).empty());
  std::remove(path.c_str());
  std::remove(target.c_str());
}

TEST(BuildMpi, HelpNamesTheLauncherAndEveryBuildOption) {
  const Outcome r = test::run_command(std::string(VISVOL_BUILD_MPI_BIN) + " --help");
  EXPECT_EQ(r.status, 0) << r.err;
  for (const char* word :
       {"mpirun", "--output", "--range", "--lod", "--threads", "--area", "--fill-nodata", "--split"}) {
    EXPECT_NE(r.out.find(word), std::string::npos) << word;
  }
}

}  // namespace
}  // namespace visvol
