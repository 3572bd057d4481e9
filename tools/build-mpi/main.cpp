// visvol-build-mpi: `visvol build DEM -o PACK`, split among the processes of
// an MPI job, from two processes on a laptop to a cluster.
//
//   mpirun -np N visvol-build-mpi DEM -o PACK [visvol build's options]
//
// Rank 0 imports the DEM and sends the terrain to every rank. Each rank builds
// its share of every level's rows (storage::build_pack_share: its band of
// rows) and writes its tiles into
// the pack's temporary file with MPI-IO, at offsets every rank knows from the
// layout. Rank 0 gathers the tiles' checksums, writes the tables and renames
// the pack into place. The pack is `visvol build`'s, byte for byte (but for
// its build time). PACK's directory must be one every rank sees (the DEM is
// read by rank 0 only).
//
// --split observers (the default): a rank computes the hulls of its band's
// observers only, and sends the sums over the rows of other bands within
// their range to the ranks that own them (MpiRowExchange): each hull once in
// the whole job. --split rows: a rank computes the hulls of every observer
// within range of its band, its neighbours' too, and exchanges nothing.
//
// A rank that fails prints why and ends the job (MPI_Abort); mpirun ends a job
// one of whose ranks was killed. Either way rank 0 removes the temporary (on
// the SIGTERM mpirun sends, or before its own abort) and no pack is written.
//
// Exit status: 0 success, 1 failure while working, 2 bad arguments or input.
#include <mpi.h>
#include <sched.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "base/arguments.hpp"
#include "base/cli_numbers.hpp"
#include "base/terminal_text.hpp"
#include "base/version.hpp"
#include "build_cli.hpp"
#include "cli.hpp"
#include "io/atomic_file.hpp"
#include "mpi_comm.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_writer.hpp"

namespace visvol::cli {
namespace {

using Clock = std::chrono::steady_clock;

// Prints "visvol-build-mpi: <message>" and returns the exit status for it.
int fail_here(const Status& status) {
  std::fprintf(stderr, "visvol-build-mpi: %s\n", status.message().c_str());
  return exit_code(status);
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A rank's own tiles, written into the shared temporary at their places.
class MpiTileSink final : public storage::TileSink {
 public:
  MpiTileSink(const storage::TilePlacement& placement, MPI_File file, const std::string& path)
      : placement_(placement), file_(file), path_(path) {}

  Status write_tile(int level, storage::Layer layer, int tx, int ty, const void* payload, std::size_t bytes) override {
    const auto t0 = Clock::now();
    const Result<storage::TilePlacement::Stored> stored =
        placement_.store(level, layer, tx, ty, payload, bytes,
                         [&](const void* data, std::size_t n, std::uint64_t at) { return write_at(data, n, at); });
    if (!stored.ok()) return stored.status().with_context(path_);
    indices.push_back(stored->index);
    checksums.push_back(stored->crc32c);
    bytes_written += placement_.tiles[stored->index].bytes;
    write_s += seconds_since(t0);
    return Status::ok_status();
  }

  std::vector<std::uint64_t> indices;    // of the tiles written (placement entries), in the order written
  std::vector<std::uint32_t> checksums;  // theirs
  std::uint64_t bytes_written = 0;
  double write_s = 0;

 private:
  Status write_at(const void* data, std::size_t bytes, std::uint64_t offset) {
    MPI_Status st;
    // a tile is at most a few MiB: one call
    const int rc =
        MPI_File_write_at(file_, static_cast<MPI_Offset>(offset), data, static_cast<int>(bytes), MPI_BYTE, &st);
    int count = 0;
    if (rc == MPI_SUCCESS) MPI_Get_count(&st, MPI_BYTE, &count);
    if (rc != MPI_SUCCESS || static_cast<std::size_t>(count) != bytes) {
      return output_error("writing " + std::to_string(bytes) + " bytes at " + std::to_string(offset) +
                          " failed: " + mpi_error_text(rc));
    }
    return Status::ok_status();
  }

  const storage::TilePlacement& placement_;
  MPI_File file_;
  std::string path_;
};

// One rank's figures, gathered to rank 0 for the report.
enum Figure : std::size_t {
  kFpS,
  kHullS,
  kScatterS,
  kTffS,
  kWriteS,
  kShareS,
  kWaitS,
  kLevel0Rows,
  kTiles,
  kMibWritten,
  kThreads,
  kSumsS,       // waiting for and adding the other ranks' sums (--split observers)
  kSumsMibOut,  // the sums sent
  kFigureCount
};
using RankFigures = std::array<double, kFigureCount>;

void print_ranks(const std::vector<double>& all, double exchanged_bytes, double exchange_s) {
  std::printf(
      "\nrank  threads  level-0 rows  F_p s   hull s  scatter s  sums s  tff s   write s  share s  wait s  tiles  "
      "MiB written  sums MiB sent\n");
  for (std::size_t r = 0; r < all.size() / kFigureCount; ++r) {
    const double* f = &all[r * kFigureCount];
    std::printf("%4zu  %7.0f  %12.0f  %6.2f  %6.2f  %9.2f  %6.2f  %6.2f  %7.2f  %7.2f  %6.2f  %5.0f  %11.1f  %13.2f\n",
                r, f[kThreads], f[kLevel0Rows], f[kFpS], f[kHullS], f[kScatterS], f[kSumsS], f[kTffS], f[kWriteS],
                f[kShareS], f[kWaitS], f[kTiles], f[kMibWritten], f[kSumsMibOut]);
  }
  std::printf(
      "exchanged  %.2f MiB between ranks (terrain out, checksums and figures back) in %.2f s, besides the sums "
      "above\n",
      exchanged_bytes / (1024.0 * 1024.0), exchange_s);
}

// Worker threads a rank takes for --threads 0: the cores it may run on,
// shared with the ranks of its node that may run on any of them (mpirun binds
// ranks to a core or a socket, or not at all; a cpuset may hold every rank of
// a node on the same cores).
int threads_per_rank(const Comm& world) {
  cpu_set_t mine;
  CPU_ZERO(&mine);
  if (::sched_getaffinity(0, sizeof mine, &mine) != 0) {
    for (unsigned c = 0; c < std::max(1u, std::thread::hardware_concurrency()) && c < CPU_SETSIZE; ++c) {
      CPU_SET(c, &mine);
    }
  }
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(world.comm, MPI_COMM_TYPE_SHARED, world.rank, MPI_INFO_NULL, &node);
  int on_node = 1;
  if (node != MPI_COMM_NULL) MPI_Comm_size(node, &on_node);
  std::vector<cpu_set_t> sets(static_cast<std::size_t>(on_node), mine);
  if (node != MPI_COMM_NULL) {
    MPI_Allgather(&mine, sizeof mine, MPI_BYTE, sets.data(), sizeof mine, MPI_BYTE, node);
    MPI_Comm_free(&node);
  }
  int sharing = 0;  // ranks (this one too) that may run on this rank's cores
  for (cpu_set_t& other : sets) {
    cpu_set_t both;
    CPU_AND(&both, &other, &mine);
    if (CPU_COUNT(&both) > 0) ++sharing;
  }
  return std::max(1, CPU_COUNT(&mine) / std::max(1, sharing));
}

// The rank that failed stops the job: message first, then the abort (which
// makes mpirun end the others). Rank 0 drops its temporary before.
[[noreturn]] void abort_job(const Comm& world, const Status& status, std::unique_ptr<storage::PackWriter>& writer) {
  std::fprintf(stderr, "visvol-build-mpi: rank %d of %d: %s\n", world.rank, world.size, status.message().c_str());
  std::fflush(stderr);
  writer.reset();  // removes the temporary (rank 0)
  MPI_Abort(world.comm, exit_code(status));
  std::_Exit(kExitFailure);  // MPI_Abort does not return
}

// Ends a run whose failure every rank agreed on: rank 0 says why.
int agreed_failure(const Comm& world, const Status& status) {
  return world.rank == 0 ? fail_here(status) : exit_code(status);
}

// Rank 0 imports and checks the DEM; every rank then has the terrain, the
// field's and the pack's parameters and the plan, rank 0's exactly.
struct Job {
  PreparedBuild build;
  storage::PackBuildParams params;
  storage::PackPlan plan;
  double exchanged_bytes = 0, exchange_s = 0;
};
Status prepare(const Comm& world, const BuildOptions& o, Job& job) {
  Status ready = Status::ok_status();
  PreparedBuild& b = job.build;
  if (world.rank == 0) {
    Result<PreparedBuild> prepared = prepare_build(o);
    if (prepared.ok()) {
      for (const std::string& w : prepared->warnings)
        std::fprintf(stderr, "visvol-build-mpi: warning: %s\n", terminal_safe(w).c_str());
      b = std::move(*prepared);
    } else {
      ready = prepared.status();
    }
  }
  VISVOL_RETURN_IF_ERROR(world.agree(ready));
  const auto t0 = Clock::now();
  job.exchanged_bytes += world.broadcast(b.terrain);
  job.exchanged_bytes += world.broadcast(b.params.weights);
  // the planning margin rank 0 decided (given, or the one an --area crop needs)
  job.exchanged_bytes += world.broadcast(b.input.planning_margin_m);
  job.exchange_s += seconds_since(t0);
  if (world.rank != 0) {
    Result<fields::FieldParams> params = make_params(o, b.terrain, &b.params.weights);
    ready = params.ok() ? Status::ok_status() : params.status();
    if (params.ok()) b.params = std::move(*params);
  }
  VISVOL_RETURN_IF_ERROR(world.agree(ready));
  job.params = pack_build_params(o, b);
  Result<storage::PackPlan> plan = storage::plan_pack(b.terrain, job.params);
  VISVOL_RETURN_IF_ERROR(world.agree(plan.ok() ? Status::ok_status() : plan.status()));
  job.plan = std::move(*plan);
  // the plan holds every level's terrain; rank 0 keeps the DEM for its summary
  if (world.rank != 0) std::vector<float>().swap(b.terrain.height_m);
  return Status::ok_status();
}

// This rank's figures.
RankFigures figures_of(const Comm& world, const Job& job, const storage::PackBuildReport& report,
                       const MpiTileSink& sink, int threads) {
  RankFigures f{};
  for (const fields::BuildStats& s : report.levels) {
    f[kFpS] += s.wall_s;
    f[kHullS] += s.hull_s;
    f[kScatterS] += s.scatter_s;
    f[kSumsS] += s.exchange_s;
    f[kSumsMibOut] += static_cast<double>(s.sent_bytes) / (1024.0 * 1024.0);
  }
  const fields::Heightfield& t = job.build.terrain;
  const fields::RowBand rows = storage::share_field_rows(t.nx, t.ny, storage::BuildShare{world.rank, world.size});
  f[kLevel0Rows] = rows.end - rows.first;
  f[kTffS] = report.tff_s;
  f[kWriteS] = sink.write_s;
  f[kTiles] = static_cast<double>(sink.indices.size());
  f[kMibWritten] = static_cast<double>(sink.bytes_written) / (1024.0 * 1024.0);
  f[kThreads] = threads;
  return f;
}

int run(const Comm& world, BuildOptions o, bool by_observers) {
  const auto t0 = Clock::now();
  if (o.threads == 0) o.threads = threads_per_rank(world);
  Job job;
  if (const Status st = prepare(world, o, job); !st.ok()) return agreed_failure(world, st);
  MpiRowExchange sums(world);
  if (by_observers) {  // level 0 has the most rows; every rank decides the same
    if (const Status st = sums.check_rows(job.plan.inputs.front().terrain.ny); !st.ok()) {
      return agreed_failure(world, st);
    }
  }

  // Rank 0 makes the temporary in a private directory; every rank opens it by name.
  std::unique_ptr<storage::PackWriter> writer;
  std::string write_path;
  Status made = Status::ok_status();
  if (world.rank == 0) {
    Result<std::unique_ptr<storage::PackWriter>> w = storage::PackWriter::create_shared(o.out, job.plan.layout);
    if (w.ok()) {
      writer = std::move(*w);
      write_path = writer->write_path();
    } else {
      made = w.status();
    }
  }
  if (const Status st = world.agree(made); !st.ok()) return agreed_failure(world, st);
  job.exchanged_bytes += world.broadcast(write_path);
  if (const Status st = world.agree(check_shared_file(write_path)); !st.ok()) return agreed_failure(world, st);
  std::optional<storage::TilePlacement> own;  // rank 0 has the writer's
  if (world.rank != 0) {
    Result<storage::TilePlacement> placed = storage::place_tiles(job.plan.layout);
    if (!placed.ok()) abort_job(world, placed.status(), writer);
    own = std::move(*placed);
  }
  const storage::TilePlacement& placement = world.rank == 0 ? writer->placement() : *own;
  MPI_File file = MPI_FILE_NULL;
  if (const Status st = open_for_writing(world, write_path, &file); !st.ok()) abort_job(world, st, writer);

  // This rank's share.
  MpiTileSink sink(placement, file, write_path);
  storage::PackBuildReport report;
  {
    std::unique_ptr<Progress> progress;
    if (world.rank == 0) progress = std::make_unique<Progress>("building " + o.out + " (rank 0's share)");
    const Status built = storage::build_pack_share(
        job.plan, job.params, storage::BuildShare{world.rank, world.size, by_observers ? &sums : nullptr}, sink,
        [&](double f) {
          if (progress) progress->update(f);
        },
        &report);
    if (!built.ok()) abort_job(world, built, writer);
    if (progress) progress->finish();
  }
  RankFigures mine = figures_of(world, job, report, sink, o.threads);
  mine[kShareS] = seconds_since(t0);
  const auto t_wait = Clock::now();
  if (const Status st = close_file(&file, write_path); !st.ok()) abort_job(world, st, writer);  // every rank's tiles
  mine[kWaitS] = seconds_since(t_wait);

  // The checksums, gathered in rank order; rank 0 writes the tables.
  const auto t_x = Clock::now();
  const std::vector<std::uint64_t> indices = world.gather(sink.indices, &job.exchanged_bytes);
  const std::vector<std::uint32_t> checksums = world.gather(sink.checksums, &job.exchanged_bytes);
  const std::vector<double> figures = world.gather(std::vector<double>(mine.begin(), mine.end()), &job.exchanged_bytes);
  job.exchange_s += seconds_since(t_x);
  Status done = Status::ok_status();
  if (world.rank == 0) {
    for (std::size_t n = 0; n < indices.size() && done.ok(); ++n) {
      done = writer->add_written_tile(indices[n], checksums[n]);
    }
    Result<std::string> meta =
        storage::pack_metadata(job.build.terrain, job.params, build_source_json(o, job.build), job.plan);
    if (done.ok()) done = meta.ok() ? writer->finish(*meta) : meta.status();
  }
  if (const Status st = world.agree(done); !st.ok()) return agreed_failure(world, st);
  if (world.rank == 0) {
    report.file_bytes = writer->file_bytes();
    report.planning.recorded = true;
    report.wall_s = seconds_since(t0);
    print_pack_summary(o, job.build, report);
    std::printf("(the level times above are rank 0's share; every rank's below)\n");
    print_ranks(figures, job.exchanged_bytes, job.exchange_s);
    std::printf("total      %.2f s on %d rank%s\n", report.wall_s, world.size, world.size == 1 ? "" : "s");
  }
  return kExitOk;
}

}  // namespace
}  // namespace visvol::cli

int main(int argc, char** argv) {
  using namespace visvol::cli;
  if (visvol::print_version_if_asked(argc, argv, "visvol-build-mpi")) return 0;
  if (const int empty = visvol::first_empty_argument(argc, argv); empty > 0) {
    std::fprintf(stderr, "visvol-build-mpi: %s (try --help)\n", visvol::empty_argument_problem(argv, empty).c_str());
    return 2;
  }
  // mpirun ends a failed job with SIGTERM: rank 0's temporary goes with it
  visvol::install_output_cleanup_on_signals();
  // the worker threads never call MPI: the main thread makes every call
  int provided = MPI_THREAD_SINGLE;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const Comm world(MPI_COMM_WORLD);
  if (provided < MPI_THREAD_FUNNELED) {
    if (world.rank == 0) std::fprintf(stderr, "visvol-build-mpi: this MPI does not allow threads beside MPI calls\n");
    MPI_Finalize();
    return kExitFailure;
  }
  BuildOptions o;
  CLI::App app{
      "visvol-build-mpi: visvol build split among the processes of an MPI job (mpirun -np N visvol-build-mpi DEM -o "
      "PACK ...); the same pack, byte for byte. PACK's directory must be seen by every rank; the DEM is read by rank "
      "0"};
  app.set_version_flag("--version", visvol::version_line("visvol-build-mpi"));
  add_build_options(&app, o);
  app.add_option("-o,--output", o.out, "Field pack to write (written whole or not at all)")->required();
  app.get_option("--threads")
      ->description(
          "Worker threads per rank; 0: the cores mpirun bound the rank to, or its node's cores shared among the node's "
          "ranks");
  std::string split = "observers";
  app.add_option("--split", split,
                 "observers: a rank computes its band's hulls only and sends the sums over other bands' rows; rows: "
                 "it computes every hull within range of its band and sends nothing")
      ->check(CLI::IsMember({"observers", "rows"}))
      ->capture_default_str();
  int code = kExitOk;
  visvol::decimal_numbers(app);  // "010" is ten, not octal eight
  try {
    app.parse(argc, argv);
    code = run(world, o, split == "observers");
  } catch (const CLI::ParseError& e) {
    if (world.rank == 0) {
      if (e.get_exit_code() == 0) {
        std::printf("%s", app.help().c_str());
      } else {
        std::fprintf(stderr, "visvol-build-mpi: %s (try --help)\n", e.what());
      }
    }
    code = e.get_exit_code() == 0 ? kExitOk : kExitUsage;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "visvol-build-mpi: rank %d: out of memory\n", world.rank);
    MPI_Abort(MPI_COMM_WORLD, kExitFailure);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "visvol-build-mpi: rank %d: internal error: %s\n", world.rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, kExitFailure);
  }
  MPI_Finalize();
  return code;
}
