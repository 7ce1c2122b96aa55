// TetGen file reader: a count header, then one record per line, '#' comments anywhere
// (format: https://wias-berlin.de/software/tetgen/fformats.html).
#include "runtime/mesh/tetgen_reader.h"

#include <algorithm>
#include <filesystem>

#include "runtime/mesh/line_reader.h"

namespace simit::runtime {

namespace {

// A header's count is untrusted: reserving it whole would let one bad digit exhaust memory.
constexpr int kMaxReserve = 1 << 20;

std::string strip_extension(const std::string& path) {
  for (const char* ext : {".node", ".ele", ".face", ".edge"}) {
    std::string e = ext;
    if (path.size() > e.size() && path.compare(path.size() - e.size(), e.size(), e) == 0)
      return path.substr(0, path.size() - e.size());
  }
  return path;
}

// Optional header field `i` (TetGen defaults missing trailing fields) restricted to [lo, hi].
int header_field(const LineReader& in, size_t i, int fallback, int lo, int hi,
                 const std::string& what) {
  if (i >= in.size()) return fallback;
  int value = in.count(i, what);
  if (value < lo || value > hi) in.fail_token(i, what);
  return value;
}

// The next of `total` records, or an error saying how many were found.
void next_record(LineReader& in, int index, int total, const char* noun) {
  if (!in.next())
    in.fail("expected " + std::to_string(total) + " " + noun +
            " records (the header's count), found end of file after " + std::to_string(index));
}

void expect_file_end(LineReader& in, int total, const char* noun) {
  if (in.next())
    in.fail("expected end of file after " + std::to_string(total) + " " + noun +
            " records (the header's count), got another record");
}

struct IndexRange {
  int base;
  int vertex_count;
};

int vertex_index(const LineReader& in, size_t i, IndexRange range) {
  std::string what = "a vertex index in [" + std::to_string(range.base) + ", " +
                     std::to_string(range.base + range.vertex_count) + ")";
  long long v = in.integer(i, what);
  if (v < range.base || v >= static_cast<long long>(range.base) + range.vertex_count)
    in.fail_token(i, what);
  return static_cast<int>(v - range.base);
}

// Reads `count` trailing numeric columns (attributes, markers) from token `first` on.
void skip_numbers(const LineReader& in, size_t first, int count, const std::string& what) {
  for (int k = 0; k < count; ++k) in.number(first + k, what);
}

IndexRange read_nodes(const std::string& path, Mesh& mesh) {
  LineReader in(path, '#');
  in.require_next("a header 'vertex-count 3 attribute-count marker-count'");
  int n = in.count(0, "a vertex count");
  header_field(in, 1, 3, 3, 3, "the dimension 3");
  int attributes = header_field(in, 2, 0, 0, 1 << 20, "an attribute count");
  int markers = header_field(in, 3, 0, 0, 1, "a boundary-marker count (0 or 1)");
  if (in.size() > 4) in.expect_end(4, "the header");
  mesh.points.reserve(std::min(n, kMaxReserve));
  int base = 0;
  for (int i = 0; i < n; ++i) {
    next_record(in, i, n, "vertex");
    if (i == 0) {
      base = static_cast<int>(in.integer(0, "the first vertex index, 0 or 1"));
      if (base != 0 && base != 1) in.fail_token(0, "the first vertex index, 0 or 1");
    } else if (in.integer(0, "vertex index " + std::to_string(base + i)) != base + i) {
      in.fail_token(0, "vertex index " + std::to_string(base + i));
    }
    std::string of = " of vertex " + std::to_string(base + i);
    Point p{};
    for (int k = 0; k < 3; ++k) p[k] = in.number(1 + k, std::string(1, "xyz"[k]) + of);
    skip_numbers(in, 4, attributes + markers, "an attribute or marker" + of);
    in.expect_end(4 + attributes + markers, "vertex " + std::to_string(base + i));
    mesh.points.push_back(p);
  }
  expect_file_end(in, n, "vertex");
  mesh.point_numbers.first = base;
  return {base, n};
}

void read_tets(const std::string& path, IndexRange range, Mesh& mesh) {
  LineReader in(path, '#');
  in.require_next("a header 'tet-count 4 attribute-count'");
  int n = in.count(0, "a tet count");
  int nodes = header_field(in, 1, 4, 4, 10, "the vertices per tet, 4 or 10");
  if (nodes != 4 && nodes != 10) in.fail_token(1, "the vertices per tet, 4 or 10");
  int attributes = header_field(in, 2, 0, 0, 1 << 20, "an attribute count");
  if (in.size() > 3) in.expect_end(3, "the header");
  mesh.tets.reserve(std::min(n, kMaxReserve));
  for (int i = 0; i < n; ++i) {
    next_record(in, i, n, "tet");
    long long number = in.integer(0, "a tet index");
    if (i == 0) mesh.tet_numbers.first = number;  // messages count on from the first
    Tet t{};
    for (int k = 0; k < nodes; ++k) {
      int v = vertex_index(in, 1 + k, range);
      if (k < 4) t[k] = v;
    }
    skip_numbers(in, 1 + nodes, attributes, "a tet attribute");
    in.expect_end(1 + nodes + attributes, "a tet record");
    mesh.tets.push_back(t);
  }
  expect_file_end(in, n, "tet");
}

std::string with_article(const char* noun) {
  return (std::string("aeiou").find(noun[0]) == std::string::npos ? "a " : "an ") +
         std::string(noun);
}

// .face and .edge records: index, N vertices, an optional marker and, with TetGen's -nn,
// `adjacent` neighbouring-tet columns that Simit does not use.
template <size_t N>
void read_simplices(const std::string& path, IndexRange range, size_t adjacent, const char* noun,
                    std::vector<std::array<int, N>>& out, Numbering& numbers) {
  LineReader in(path, '#');
  in.require_next(std::string("a header '") + noun + "-count marker-count'");
  int n = in.count(0, with_article(noun) + " count");
  int markers = header_field(in, 1, 0, 0, 1, "a boundary-marker count (0 or 1)");
  if (in.size() > 2) in.expect_end(2, "the header");
  out.reserve(std::min(n, kMaxReserve));
  size_t plain = 1 + N + markers;
  for (int i = 0; i < n; ++i) {
    next_record(in, i, n, noun);
    long long number = in.integer(0, with_article(noun) + " index");
    if (i == 0) numbers.first = number;
    std::array<int, N> e{};
    for (size_t k = 0; k < N; ++k) e[k] = vertex_index(in, 1 + k, range);
    if (markers) in.integer(1 + N, "a boundary marker");
    size_t columns = in.size() == plain + adjacent ? plain + adjacent : plain;
    for (size_t k = plain; k < columns; ++k) in.integer(k, "an adjacent tet index");
    in.expect_end(columns, with_article(noun) + " record");
    out.push_back(e);
  }
  expect_file_end(in, n, noun);
}

bool exists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace

Mesh read_tetgen(const std::string& path) {
  std::string base = strip_extension(path);
  Mesh mesh;
  IndexRange range = read_nodes(base + ".node", mesh);
  if (exists(base + ".ele")) read_tets(base + ".ele", range, mesh);
  if (exists(base + ".face"))
    read_simplices(base + ".face", range, 2, "face", mesh.triangles, mesh.triangle_numbers);
  if (exists(base + ".edge"))
    read_simplices(base + ".edge", range, 1, "edge", mesh.edges, mesh.edge_numbers);
  return mesh;
}

}  // namespace simit::runtime
