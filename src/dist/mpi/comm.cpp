// The distributed layer's use of MPI (dist/mpi/comm.h).
#include "dist/mpi/comm.h"

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace simit::dist::mpi {

namespace {

void check(int status, const char* what) {
  if (status == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(status, text, &length);
  throw CommError(std::string(what) + " failed: " + std::string(text, static_cast<size_t>(length)));
}

// The tag of ghost refreshes: each pair of ranks exchanges at most one message each way per
// refresh, and MPI keeps a pair's messages in order, so one tag tells them apart.
constexpr int kGhostTag = 17;

// A datatype of one element (element_bytes bytes), so that counts are in elements and a large
// set's byte count never has to fit an int.
class ElementType {
 public:
  explicit ElementType(size_t element_bytes) {
    if (element_bytes == 0 || element_bytes > static_cast<size_t>(INT_MAX))
      throw std::invalid_argument("element size of " + std::to_string(element_bytes) +
                                  " bytes: it must be 1 to " + std::to_string(INT_MAX));
    check(MPI_Type_contiguous(static_cast<int>(element_bytes), MPI_BYTE, &type_),
          "MPI_Type_contiguous");
    check(MPI_Type_commit(&type_), "MPI_Type_commit");
  }
  ~ElementType() { MPI_Type_free(&type_); }
  ElementType(const ElementType&) = delete;
  ElementType& operator=(const ElementType&) = delete;
  MPI_Datatype get() const { return type_; }

 private:
  MPI_Datatype type_ = MPI_DATATYPE_NULL;
};

int element_count(size_t count, const char* what) {
  if (count > static_cast<size_t>(INT_MAX))
    throw CommError(std::string(what) + ": " + std::to_string(count) +
                    " elements in one message, more than MPI counts");
  return static_cast<int>(count);
}

}  // namespace

Session::Session(int* argc, char*** argv) {
  check(MPI_Init(argc, argv), "MPI_Init");
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

Session::~Session() { MPI_Finalize(); }

int64_t Session::sum(int64_t value) const {
  int64_t total = 0;
  check(MPI_Allreduce(&value, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  return total;
}

int64_t Session::sum_below(int64_t value) const {
  int64_t below = 0;
  check(MPI_Exscan(&value, &below, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Exscan");
  return rank_ == 0 ? 0 : below;  // MPI leaves rank 0's undefined
}

void Session::least(std::vector<int64_t>& values) const {
  if (values.empty()) return;
  check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT64_T,
                      MPI_MIN, MPI_COMM_WORLD),
        "MPI_Allreduce");
}

std::vector<int64_t> Session::gather(int64_t value, int root) const {
  std::vector<int64_t> all(rank_ == root ? static_cast<size_t>(size_) : 0);
  check(MPI_Gather(&value, 1, MPI_INT64_T, all.data(), 1, MPI_INT64_T, root, MPI_COMM_WORLD),
        "MPI_Gather");
  return all;
}

void Session::broadcast(std::vector<int32_t>& values, int root) const {
  int64_t n = static_cast<int64_t>(values.size());
  check(MPI_Bcast(&n, 1, MPI_INT64_T, root, MPI_COMM_WORLD), "MPI_Bcast");
  values.resize(static_cast<size_t>(n));
  // In pieces that an int counts.
  constexpr int64_t kPiece = int64_t{1} << 30;
  for (int64_t at = 0; at < n; at += kPiece)
    check(MPI_Bcast(values.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_INT32_T,
                    root, MPI_COMM_WORLD),
          "MPI_Bcast");
}

std::vector<std::byte> Session::scatter(std::vector<std::vector<std::byte>> parts, int root) const {
  constexpr int kTag = 18;
  constexpr int64_t kPiece = int64_t{1} << 30;
  std::vector<int64_t> sizes(static_cast<size_t>(size_), 0);
  if (rank_ == root) {
    if (parts.size() != static_cast<size_t>(size_))
      throw std::invalid_argument("scatter: " + std::to_string(parts.size()) + " parts for " +
                                  std::to_string(size_) + " ranks");
    for (size_t r = 0; r < parts.size(); ++r) sizes[r] = static_cast<int64_t>(parts[r].size());
  }
  int64_t mine = 0;
  check(MPI_Scatter(sizes.data(), 1, MPI_INT64_T, &mine, 1, MPI_INT64_T, root, MPI_COMM_WORLD),
        "MPI_Scatter");
  if (rank_ == root) {
    for (int r = 0; r < size_; ++r) {
      if (r == root) continue;
      const std::vector<std::byte>& part = parts[static_cast<size_t>(r)];
      const auto n = static_cast<int64_t>(part.size());
      for (int64_t at = 0; at < n; at += kPiece)
        check(MPI_Send(part.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_BYTE, r,
                       kTag, MPI_COMM_WORLD),
              "MPI_Send");
    }
    return std::move(parts[static_cast<size_t>(root)]);
  }
  std::vector<std::byte> part(static_cast<size_t>(mine));
  for (int64_t at = 0; at < mine; at += kPiece)
    check(MPI_Recv(part.data() + at, static_cast<int>(std::min(kPiece, mine - at)), MPI_BYTE, root,
                   kTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Recv");
  return part;
}

void Session::refresh_ghosts(const GhostPlan& plan, std::span<std::byte> values,
                             size_t element_bytes) const {
  const ElementType type(element_bytes);
  const size_t count = values.size() / element_bytes;
  // Every index is checked before the first message, so that a bad plan fails here rather
  // than writing outside `values`.
  for (const GhostLink& link : plan.links) {
    if (link.rank < 0 || link.rank >= size_ || link.rank == rank_)
      throw std::invalid_argument("ghost plan of rank " + std::to_string(rank_) +
                                  " has a link to rank " + std::to_string(link.rank));
    for (const auto* list : {&link.send, &link.recv})
      for (int32_t i : *list)
        if (i < 0 || static_cast<size_t>(i) >= count)
          throw std::invalid_argument("ghost plan of rank " + std::to_string(rank_) +
                                      " names element " + std::to_string(i) + " of " +
                                      std::to_string(count));
  }
  const size_t links = plan.links.size();
  std::vector<std::vector<std::byte>> out(links), in(links);
  std::vector<MPI_Request> requests;
  requests.reserve(2 * links);
  // The receives first, so that the sends find them posted.
  for (size_t l = 0; l < links; ++l) {
    const GhostLink& link = plan.links[l];
    if (link.recv.empty()) continue;
    in[l].resize(link.recv.size() * element_bytes);
    check(MPI_Irecv(in[l].data(), element_count(link.recv.size(), "MPI_Irecv"), type.get(),
                    link.rank, kGhostTag, MPI_COMM_WORLD, &requests.emplace_back()),
          "MPI_Irecv");
  }
  for (size_t l = 0; l < links; ++l) {
    const GhostLink& link = plan.links[l];
    if (link.send.empty()) continue;
    out[l].resize(link.send.size() * element_bytes);
    for (size_t k = 0; k < link.send.size(); ++k)
      std::memcpy(out[l].data() + k * element_bytes,
                  values.data() + static_cast<size_t>(link.send[k]) * element_bytes, element_bytes);
    check(MPI_Isend(out[l].data(), element_count(link.send.size(), "MPI_Isend"), type.get(),
                    link.rank, kGhostTag, MPI_COMM_WORLD, &requests.emplace_back()),
          "MPI_Isend");
  }
  check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
        "MPI_Waitall");
  for (size_t l = 0; l < links; ++l) {
    const GhostLink& link = plan.links[l];
    for (size_t k = 0; k < link.recv.size(); ++k)
      std::memcpy(values.data() + static_cast<size_t>(link.recv[k]) * element_bytes,
                  in[l].data() + k * element_bytes, element_bytes);
  }
}

std::vector<double> Session::all_gather(std::span<const double> values) const {
  const int mine = element_count(values.size(), "MPI_Allgatherv");
  std::vector<int> counts(static_cast<size_t>(size_)), offsets(counts.size());
  check(MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD),
        "MPI_Allgather");
  int64_t total = 0;
  for (size_t r = 0; r < counts.size(); ++r) {
    if (total + counts[r] > INT_MAX)
      throw CommError("MPI_Allgatherv: more than an int counts, " + std::to_string(total) + "+");
    offsets[r] = static_cast<int>(total);
    total += counts[r];
  }
  std::vector<double> all(static_cast<size_t>(total));
  check(MPI_Allgatherv(values.data(), mine, MPI_DOUBLE, all.data(), counts.data(), offsets.data(),
                       MPI_DOUBLE, MPI_COMM_WORLD),
        "MPI_Allgatherv");
  return all;
}

std::vector<std::byte> Session::gather_owned(std::span<const int32_t> global,
                                             std::span<const std::byte> values,
                                             size_t element_bytes, int32_t whole, int root) const {
  const ElementType type(element_bytes);
  if (whole < 0) throw std::invalid_argument("gather of " + std::to_string(whole) + " elements");
  if (values.size() / element_bytes < global.size())
    throw std::invalid_argument("gather: rank " + std::to_string(rank_) + " gives " +
                                std::to_string(global.size()) + " elements but values for " +
                                std::to_string(values.size() / element_bytes));
  const int mine = element_count(global.size(), "MPI_Gatherv");
  const bool is_root = rank_ == root;
  std::vector<int> counts(is_root ? static_cast<size_t>(size_) : 0), offsets(counts.size());
  check(MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, root, MPI_COMM_WORLD),
        "MPI_Gather");
  // The counts must add up to the whole before the gather (else it could not be laid out);
  // root tells every rank, and every rank throws alike.
  int64_t total = 0;
  for (size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = static_cast<int>(std::min<int64_t>(total, INT_MAX));
    total += counts[r];
  }
  int64_t given = total;
  check(MPI_Bcast(&given, 1, MPI_INT64_T, root, MPI_COMM_WORLD), "MPI_Bcast");
  if (given != whole)
    throw std::invalid_argument("gather: the ranks own " + std::to_string(given) +
                                " elements, not the whole's " + std::to_string(whole));
  std::vector<int32_t> all_global(is_root ? static_cast<size_t>(whole) : 0);
  std::vector<std::byte> all_values(all_global.size() * element_bytes);
  check(MPI_Gatherv(global.data(), mine, MPI_INT32_T, all_global.data(), counts.data(),
                    offsets.data(), MPI_INT32_T, root, MPI_COMM_WORLD),
        "MPI_Gatherv");
  check(MPI_Gatherv(values.data(), mine, type.get(), all_values.data(), counts.data(),
                    offsets.data(), type.get(), root, MPI_COMM_WORLD),
        "MPI_Gatherv");
  if (!is_root) return {};
  std::vector<std::byte> result(all_values.size());
  std::vector<uint8_t> seen(static_cast<size_t>(whole), 0);
  for (size_t i = 0; i < all_global.size(); ++i) {
    const int32_t g = all_global[i];
    if (g < 0 || g >= whole || seen[static_cast<size_t>(g)])
      throw std::invalid_argument("gather: element " + std::to_string(g) + " of " +
                                  std::to_string(whole) +
                                  (g < 0 || g >= whole ? " is out of range" : " is given twice"));
    seen[static_cast<size_t>(g)] = 1;
    std::memcpy(result.data() + static_cast<size_t>(g) * element_bytes,
                all_values.data() + i * element_bytes, element_bytes);
  }
  return result;
}

bool Session::any(bool flag) const {
  int mine = flag ? 1 : 0, result = 0;
  check(MPI_Allreduce(&mine, &result, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD), "MPI_Allreduce");
  return result != 0;
}

void Session::wait_for_abort() const {
  // A barrier the failing rank never joins: the abort ends it.
  for (;;) MPI_Barrier(MPI_COMM_WORLD);
}

void Session::abort(int status) const {
  MPI_Abort(MPI_COMM_WORLD, status);
  std::abort();  // MPI_Abort does not return; the compiler is told so
}

}  // namespace simit::dist::mpi
