// visvol-build-mpi: `visvol build DEM -o PACK`, split among the processes of
// an MPI job, from two processes on a laptop to a cluster.
//
//   mpirun -np N visvol-build-mpi DEM -o PACK [visvol build's options]
//
// Rank 0 imports the DEM and sends the terrain to every rank. Each rank builds
// its share of every level's rows (storage::build_pack_share: its band of
// rows, with the observers within range around it) and writes its tiles into
// the pack's temporary file with MPI-IO, at offsets every rank knows from the
// layout. Rank 0 gathers the tiles' checksums, writes the tables and renames
// the pack into place. The pack is `visvol build`'s, byte for byte (but for
// its build time). PACK's directory must be one every rank sees (the DEM is
// read by rank 0 only).
//
// A rank that fails prints why and ends the job (MPI_Abort); mpirun ends a job
// one of whose ranks was killed. Either way rank 0 removes the temporary (on
// the SIGTERM mpirun sends, or before its own abort) and no pack is written.
//
// Exit status: 0 success, 1 failure while working, 2 bad arguments or input.
#include <mpi.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <vector>

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
    const Result<std::size_t> index = placement_.find(level, layer, tx, ty, bytes);
    if (!index.ok()) return invalid_argument(path_ + ": " + index.status().message());
    const Result<std::uint32_t> crc =
        storage::store_tile(placement_.tiles[*index], payload, bytes,
                            [&](const void* data, std::size_t n, std::uint64_t at) { return write_at(data, n, at); });
    if (!crc.ok()) return crc.status();
    indices.push_back(*index);
    checksums.push_back(*crc);
    bytes_written += placement_.tiles[*index].bytes;
    write_s += seconds_since(t0);
    return Status::ok_status();
  }

  std::vector<std::uint64_t> indices;    // of the tiles written, in placement order
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
      return output_error(path_ + ": writing " + std::to_string(bytes) + " bytes at " + std::to_string(offset) +
                          " failed: " + mpi_error_text(rc));
    }
    return Status::ok_status();
  }

  const storage::TilePlacement& placement_;
  MPI_File file_;
  std::string path_;
};

// One rank's figures, gathered to rank 0 for the report.
struct RankFigures {
  double fp_s = 0, hull_s = 0, scatter_s = 0, tff_s = 0, write_s = 0, share_s = 0, wait_s = 0;
  double level0_rows = 0, hull_cells = 0, bytes_written = 0, tiles = 0, threads = 0;
};
constexpr int kFigureCount = sizeof(RankFigures) / sizeof(double);
static_assert(sizeof(RankFigures) == kFigureCount * sizeof(double));

void print_ranks(const std::vector<RankFigures>& ranks, double exchanged_bytes, double exchange_s) {
  std::printf(
      "\nrank  threads  level-0 rows  F_p s   hull s  scatter s  tff s   write s  share s  wait s  tiles  "
      "MiB written\n");
  for (std::size_t r = 0; r < ranks.size(); ++r) {
    const RankFigures& f = ranks[r];
    std::printf("%4zu  %7.0f  %12.0f  %6.2f  %6.2f  %9.2f  %6.2f  %7.2f  %7.2f  %6.2f  %5.0f  %11.1f\n", r, f.threads,
                f.level0_rows, f.fp_s, f.hull_s, f.scatter_s, f.tff_s, f.write_s, f.share_s, f.wait_s, f.tiles,
                f.bytes_written / (1024.0 * 1024.0));
  }
  std::printf("exchanged  %.2f MiB between ranks (terrain out, checksums and figures back) in %.2f s\n",
              exchanged_bytes / (1024.0 * 1024.0), exchange_s);
}

// Worker threads a rank takes for --threads 0: the cores of its node shared
// among the ranks on that node.
int threads_per_rank(const Comm& world) {
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(world.comm, MPI_COMM_TYPE_SHARED, world.rank, MPI_INFO_NULL, &node);
  int on_node = 1;
  if (node != MPI_COMM_NULL) {
    MPI_Comm_size(node, &on_node);
    MPI_Comm_free(&node);
  }
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, cores / std::max(1, on_node));
}

// The job's rank that failed stops it: message first, then the abort (which
// makes mpirun end the others). Rank 0 drops its temporary before.
[[noreturn]] void abort_job(const Comm& world, const Status& status, std::unique_ptr<storage::PackWriter>& writer) {
  std::fprintf(stderr, "visvol-build-mpi: rank %d of %d: %s\n", world.rank, world.size, status.message().c_str());
  std::fflush(stderr);
  writer.reset();  // removes the temporary (rank 0)
  MPI_Abort(world.comm, status.code() == Errc::invalid_argument ? kExitUsage : kExitFailure);
  std::_Exit(kExitFailure);  // MPI_Abort does not return
}

int run(const Comm& world, BuildOptions o) {
  const auto t0 = Clock::now();
  double exchange_s = 0, exchanged = 0;
  if (o.threads == 0) o.threads = threads_per_rank(world);

  // Rank 0 imports and checks; every rank then has its terrain and parameters.
  PreparedBuild b;
  Status ready = Status::ok_status();
  if (world.rank == 0) {
    Result<PreparedBuild> prepared = prepare_build(o);
    if (prepared.ok()) {
      b = std::move(*prepared);
    } else {
      ready = prepared.status();
    }
  }
  auto t_x = Clock::now();
  ready = world.agree(ready);
  if (!ready.ok()) return world.rank == 0 ? fail_here(ready) : exit_code(ready);
  exchanged += world.broadcast(b.terrain);
  exchanged += world.broadcast(b.params.weights);
  exchange_s += seconds_since(t_x);
  if (world.rank != 0) {
    Result<fields::FieldParams> params = make_params(o, b.terrain, &b.params.weights);
    ready = params.ok() ? Status::ok_status() : params.status();
    if (params.ok()) b.params = std::move(*params);
  }
  ready = world.agree(ready);  // the same parameters as rank 0's
  if (!ready.ok()) return world.rank == 0 ? fail_here(ready) : exit_code(ready);

  const storage::PackBuildParams pp = pack_build_params(o, b);
  Result<storage::PackPlan> plan = storage::plan_pack(b.terrain, pp);
  ready = world.agree(plan.ok() ? Status::ok_status() : plan.status());
  if (!ready.ok()) return world.rank == 0 ? fail_here(ready) : exit_code(ready);

  // Rank 0 makes the temporary (refusing links and planted files); every rank opens it by name.
  std::unique_ptr<storage::PackWriter> writer;
  std::string write_path;
  if (world.rank == 0) {
    Result<std::unique_ptr<storage::PackWriter>> w = storage::PackWriter::create(o.out, plan->layout);
    if (w.ok()) {
      writer = std::move(*w);
      write_path = writer->write_path();
    } else {
      ready = w.status();
    }
  }
  ready = world.agree(ready);
  if (!ready.ok()) return world.rank == 0 ? fail_here(ready) : exit_code(ready);
  exchanged += world.broadcast(write_path);
  Result<storage::TilePlacement> placement = storage::place_tiles(plan->layout);
  if (!placement.ok()) abort_job(world, placement.status(), writer);
  MPI_File file = MPI_FILE_NULL;
  const Status opened = open_for_writing(world, write_path, &file);
  if (!opened.ok()) abort_job(world, opened, writer);

  // This rank's share.
  MpiTileSink sink(*placement, file, write_path);
  storage::PackBuildReport report;
  {
    std::unique_ptr<Progress> progress;
    if (world.rank == 0) progress = std::make_unique<Progress>("building " + o.out + " (rank 0's share)");
    const Status built = storage::build_pack_share(
        *plan, pp, storage::BuildShare{world.rank, world.size}, sink,
        [&](double f) {
          if (progress) progress->update(f);
        },
        &report);
    if (!built.ok()) abort_job(world, built, writer);
    if (progress) progress->finish();
  }
  const double share_s = seconds_since(t0);
  const auto t_wait = Clock::now();
  const Status closed = close_file(&file, write_path);  // collective: every rank's tiles are written
  if (!closed.ok()) abort_job(world, closed, writer);
  const double wait_s = seconds_since(t_wait);

  // The checksums, gathered in rank order; rank 0 writes the tables.
  t_x = Clock::now();
  const std::vector<std::uint64_t> indices = world.gather(sink.indices, &exchanged);
  const std::vector<std::uint32_t> checksums = world.gather(sink.checksums, &exchanged);
  RankFigures mine;
  for (const fields::BuildStats& s : report.levels) {
    mine.fp_s += s.wall_s;
    mine.hull_s += s.hull_s;
    mine.scatter_s += s.scatter_s;
    mine.hull_cells += static_cast<double>(s.hull_cells);
  }
  const storage::TileRows rows =
      storage::share_tile_rows(storage::tile_grid(storage::Layer::visibility, b.terrain.nx, b.terrain.ny).tiles_y,
                               storage::BuildShare{world.rank, world.size});
  mine.level0_rows = std::min(b.terrain.ny, rows.end * storage::kBrickPosts) - rows.first * storage::kBrickPosts;
  mine.tff_s = report.tff_s;
  mine.write_s = sink.write_s;
  mine.share_s = share_s;
  mine.wait_s = wait_s;
  mine.bytes_written = static_cast<double>(sink.bytes_written);
  mine.tiles = static_cast<double>(sink.indices.size());
  mine.threads = o.threads;
  const std::vector<double> figures =
      world.gather(std::vector<double>(&mine.fp_s, &mine.fp_s + kFigureCount), &exchanged);
  exchange_s += seconds_since(t_x);
  Status done = Status::ok_status();
  if (world.rank == 0) {
    for (std::size_t n = 0; n < indices.size() && done.ok(); ++n)
      done = writer->add_written_tile(indices[n], checksums[n]);
    Result<std::string> meta = storage::pack_metadata(b.terrain, pp, build_source_json(o, b), *plan);
    if (done.ok()) done = meta.ok() ? writer->finish(*meta) : meta.status();
  }
  done = world.agree(done);
  if (!done.ok()) return world.rank == 0 ? fail_here(done) : exit_code(done);
  if (world.rank == 0) {
    report.file_bytes = writer->file_bytes();
    report.planning.recorded = true;
    report.wall_s = seconds_since(t0);
    print_pack_summary(o, b, report);
    std::printf("(the level times above are rank 0's share; every rank's below)\n");
    std::vector<RankFigures> ranks(static_cast<std::size_t>(world.size));
    for (std::size_t r = 0; r < ranks.size(); ++r) {
      std::copy_n(&figures[r * kFigureCount], kFigureCount, &ranks[r].fp_s);
    }
    print_ranks(ranks, exchanged, exchange_s);
    std::printf("total      %.2f s on %d ranks\n", report.wall_s, world.size);
  }
  return kExitOk;
}

}  // namespace
}  // namespace visvol::cli

int main(int argc, char** argv) {
  using namespace visvol::cli;
  if (visvol::print_version_if_asked(argc, argv, "visvol-build-mpi")) return 0;
  // mpirun ends a failed job with SIGTERM: rank 0's temporary goes with it
  visvol::install_output_cleanup_on_signals();
  MPI_Init(&argc, &argv);
  const Comm world(MPI_COMM_WORLD);
  BuildOptions o;
  CLI::App app{
      "visvol-build-mpi: visvol build split among the processes of an MPI job (mpirun -np N visvol-build-mpi DEM -o "
      "PACK ...); the same pack, byte for byte. PACK's directory must be seen by every rank; the DEM is read by rank "
      "0"};
  app.set_version_flag("--version", visvol::version_line("visvol-build-mpi"));
  add_build_options(&app, o);
  app.add_option("-o,--output", o.out, "Field pack to write (written whole or not at all)")->required();
  app.get_option("--threads")->description("Worker threads per rank, 0 for the node's cores shared among its ranks");
  int code = kExitOk;
  try {
    app.parse(argc, argv);
    code = run(world, o);
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
