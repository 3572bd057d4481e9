// The few collective steps visvol-build-mpi takes, over one communicator,
// with visvol's Status for errors. MPI calls are collective: every rank of
// the communicator makes each call, in the same order.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/heightfield.hpp"
#include "fields/visibility_builder.hpp"

namespace visvol::cli {

std::string mpi_error_text(int code);

struct Comm {
  explicit Comm(MPI_Comm c);
  MPI_Comm comm;
  int rank = 0, size = 1;

  // Every rank's status combined: ok when all are, otherwise the status of
  // the lowest rank that failed (its message prefixed "rank R of N: " when
  // that is not rank 0), the same on every rank.
  Status agree(const Status& local) const;

  // Rank 0's value on every rank; the bytes sent to the other ranks.
  double broadcast(std::string& text) const;
  double broadcast(std::vector<float>& values) const;
  double broadcast(fields::Heightfield& terrain) const;
  double broadcast(std::optional<double>& value) const;

  // Every rank's values on rank 0, in rank order (empty elsewhere); rank 0
  // adds the bytes it received to `*received_bytes`. Counts are MPI ints: a
  // pack's tiles (about 2^24 for the largest grid) fit.
  std::vector<std::uint64_t> gather(const std::vector<std::uint64_t>& values, double* received_bytes) const;
  std::vector<std::uint32_t> gather(const std::vector<std::uint32_t>& values, double* received_bytes) const;
  std::vector<double> gather(const std::vector<double>& values, double* received_bytes) const;
};

// The sums of a build split by observers (storage::BuildShare::exchange)
// between the ranks, a rank a share: one message a row, tagged with the row.
// MPI delivers two ranks' messages of one tag in the order they were sent, so
// the levels of detail, built one after the other, never mix. Sends are
// non-blocking, on a copy kept until finish(); the main thread makes every call.
class MpiRowExchange final : public fields::RowExchange {
 public:
  explicit MpiRowExchange(const Comm& world);
  MpiRowExchange(const MpiRowExchange&) = delete;
  MpiRowExchange& operator=(const MpiRowExchange&) = delete;
  ~MpiRowExchange() override;  // waits for sends still in flight

  // Whether rows 0..rows-1 fit this MPI's message tags: checked before a
  // build, not hours into it.
  Status check_rows(int rows) const;

  Status send(int to, int j, const std::int32_t* sums, std::size_t count) override;
  Status receive(int from, int j, std::int32_t* sums, std::size_t count) override;
  Status finish() override;

 private:
  Status check(int rank, int j, std::size_t count) const;

  const Comm& world_;
  int tag_ub_ = 32767;  // the largest tag (MPI_TAG_UB); MPI promises at least this
  std::vector<std::vector<std::int32_t>> copies_;
  std::vector<MPI_Request> requests_;
};

// Whether `path` (made by rank 0, shared by all) is a regular file here: a
// rank that does not see it is on another file system.
Status check_shared_file(const std::string& path);
// Opens `path` for writing on every rank (collective).
Status open_for_writing(const Comm& world, const std::string& path, MPI_File* file);
// Collective: every rank's writes are done and flushed when it returns.
Status close_file(MPI_File* file, const std::string& path);

}  // namespace visvol::cli
