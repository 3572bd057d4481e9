#include "mpi_comm.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <limits>
#include <string>

namespace visvol::cli {

namespace {

// Large vectors go in pieces: MPI counts are ints.
constexpr std::size_t kChunk = std::size_t{1} << 26;

template <class T>
void broadcast_values(const Comm& c, T* data, std::size_t count, MPI_Datatype type) {
  for (std::size_t at = 0; at < count; at += kChunk) {
    MPI_Bcast(data + at, static_cast<int>(std::min(kChunk, count - at)), type, 0, c.comm);
  }
}

std::uint64_t broadcast_size(const Comm& c, std::uint64_t n) {
  MPI_Bcast(&n, 1, MPI_UINT64_T, 0, c.comm);
  return n;
}

template <class T>
std::vector<T> gather_values(const Comm& c, const std::vector<T>& values, MPI_Datatype type, double* received_bytes) {
  const int mine = static_cast<int>(values.size());
  std::vector<int> counts(c.rank == 0 ? static_cast<std::size_t>(c.size) : 0);
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, c.comm);
  std::vector<int> displacements(counts.size());
  std::vector<T> all;
  if (c.rank == 0) {
    int total = 0;
    for (std::size_t r = 0; r < counts.size(); ++r) {
      displacements[r] = total;
      total += counts[r];
    }
    all.resize(static_cast<std::size_t>(total));
    *received_bytes +=
        static_cast<double>((all.size() - values.size()) * sizeof(T) + (counts.size() - 1) * sizeof(int));
  }
  MPI_Gatherv(values.data(), mine, type, all.data(), counts.data(), displacements.data(), type, 0, c.comm);
  return all;
}

}  // namespace

MpiRowExchange::MpiRowExchange(const Comm& world) : world_(world) {
  void* value = nullptr;
  int found = 0;
  MPI_Comm_get_attr(world.comm, MPI_TAG_UB, &value, &found);
  if (found && value) tag_ub_ = *static_cast<int*>(value);
}

MpiRowExchange::~MpiRowExchange() {
  if (!requests_.empty()) MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
}

Status MpiRowExchange::check(int rank, int j, std::size_t count) const {
  if (rank < 0 || rank >= world_.size || rank == world_.rank) {
    return invalid_argument("row " + std::to_string(j) + ": rank " + std::to_string(rank) + " is not another rank");
  }
  if (j < 0 || j > tag_ub_) return check_rows(j + 1);
  if (count > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    return invalid_argument("row " + std::to_string(j) + ": " + std::to_string(count) +
                            " sums are too many for one message");
  }
  return Status::ok_status();
}

Status MpiRowExchange::check_rows(int rows) const {
  if (rows - 1 <= tag_ub_) return Status::ok_status();
  return invalid_argument("a grid of " + std::to_string(rows) + " rows is past this MPI's largest message tag " +
                          std::to_string(tag_ub_) + " (a tag a row, --split observers): use --split rows");
}

Status MpiRowExchange::send(int to, int j, const std::int32_t* sums, std::size_t count) {
  VISVOL_RETURN_IF_ERROR(check(to, j, count));
  copies_.emplace_back(sums, sums + count);  // the vector's buffer stays put when copies_ grows
  requests_.emplace_back();
  const int rc =
      MPI_Isend(copies_.back().data(), static_cast<int>(count), MPI_INT32_T, to, j, world_.comm, &requests_.back());
  if (rc != MPI_SUCCESS) return output_error("sending row " + std::to_string(j) + ": " + mpi_error_text(rc));
  return Status::ok_status();
}

Status MpiRowExchange::receive(int from, int j, std::int32_t* sums, std::size_t count) {
  VISVOL_RETURN_IF_ERROR(check(from, j, count));
  MPI_Status status;
  const int rc = MPI_Recv(sums, static_cast<int>(count), MPI_INT32_T, from, j, world_.comm, &status);
  if (rc != MPI_SUCCESS) {
    return output_error("receiving row " + std::to_string(j) + " from rank " + std::to_string(from) + ": " +
                        mpi_error_text(rc));
  }
  int received = 0;
  MPI_Get_count(&status, MPI_INT32_T, &received);
  if (static_cast<std::size_t>(received) != count) {
    return output_error("row " + std::to_string(j) + " from rank " + std::to_string(from) + ": " +
                        std::to_string(received) + " sums instead of " + std::to_string(count));
  }
  return Status::ok_status();
}

Status MpiRowExchange::finish() {
  const int rc = requests_.empty()
                     ? MPI_SUCCESS
                     : MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
  requests_.clear();
  copies_.clear();
  if (rc != MPI_SUCCESS) return output_error("sending rows: " + mpi_error_text(rc));
  return Status::ok_status();
}

std::string mpi_error_text(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  if (MPI_Error_string(code, text, &length) != MPI_SUCCESS) return "MPI error " + std::to_string(code);
  return std::string(text, static_cast<std::size_t>(length));
}

Comm::Comm(MPI_Comm c) : comm(c) {
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
}

Status Comm::agree(const Status& local) const {
  const int mine = local.ok() ? size : rank;
  int first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return Status::ok_status();
  int code = static_cast<int>(local.code());
  std::string message = local.message();
  MPI_Bcast(&code, 1, MPI_INT, first, comm);
  std::uint64_t n = message.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, first, comm);
  message.resize(n);
  MPI_Bcast(message.data(), static_cast<int>(n), MPI_CHAR, first, comm);
  if (first != 0) message = "rank " + std::to_string(first) + " of " + std::to_string(size) + ": " + message;
  return Status(static_cast<Errc>(code), message);
}

double Comm::broadcast(std::string& text) const {
  text.resize(broadcast_size(*this, text.size()));
  broadcast_values(*this, text.data(), text.size(), MPI_CHAR);
  return static_cast<double>(text.size() + 8) * (size - 1);
}

double Comm::broadcast(std::vector<float>& values) const {
  values.resize(broadcast_size(*this, values.size()));
  broadcast_values(*this, values.data(), values.size(), MPI_FLOAT);
  return static_cast<double>(values.size() * sizeof(float) + 8) * (size - 1);
}

double Comm::broadcast(fields::Heightfield& t) const {
  int grid[2] = {t.nx, t.ny};
  double place[3] = {t.spacing_m, t.origin_x, t.origin_y};
  MPI_Bcast(grid, 2, MPI_INT, 0, comm);
  MPI_Bcast(place, 3, MPI_DOUBLE, 0, comm);
  t.nx = grid[0];
  t.ny = grid[1];
  t.spacing_m = place[0];
  t.origin_x = place[1];
  t.origin_y = place[2];
  return static_cast<double>(sizeof grid + sizeof place) * (size - 1) + broadcast(t.crs_wkt) + broadcast(t.height_m);
}

double Comm::broadcast(std::optional<double>& value) const {
  double v[2] = {value ? 1.0 : 0.0, value.value_or(0.0)};
  MPI_Bcast(v, 2, MPI_DOUBLE, 0, comm);
  value = v[0] != 0 ? std::optional<double>(v[1]) : std::nullopt;
  return sizeof v * static_cast<double>(size - 1);
}

std::vector<std::uint64_t> Comm::gather(const std::vector<std::uint64_t>& values, double* received_bytes) const {
  return gather_values(*this, values, MPI_UINT64_T, received_bytes);
}
std::vector<std::uint32_t> Comm::gather(const std::vector<std::uint32_t>& values, double* received_bytes) const {
  return gather_values(*this, values, MPI_UINT32_T, received_bytes);
}
std::vector<double> Comm::gather(const std::vector<double>& values, double* received_bytes) const {
  return gather_values(*this, values, MPI_DOUBLE, received_bytes);
}

Status check_shared_file(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) return Status::ok_status();
  return output_error(path +
                      ": the build's temporary is not a regular file here (is the output's directory shared "
                      "by every rank?)");
}

Status open_for_writing(const Comm& world, const std::string& path, MPI_File* file) {
  // Rank 0 made it inside a private directory (OutputFile::create_shared):
  // nobody but this user can have put anything at that name.
  const int rc = MPI_File_open(world.comm, path.c_str(), MPI_MODE_WRONLY, MPI_INFO_NULL, file);
  if (rc != MPI_SUCCESS) return output_error(path + ": cannot open for writing: " + mpi_error_text(rc));
  return Status::ok_status();
}

Status close_file(MPI_File* file, const std::string& path) {
  const int rc = MPI_File_close(file);
  if (rc != MPI_SUCCESS) return output_error(path + ": closing after the tiles failed: " + mpi_error_text(rc));
  return Status::ok_status();
}

}  // namespace visvol::cli
