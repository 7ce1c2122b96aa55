// A distributed run's pieces of each frame (scene/output_pieces.h).
#include "scene/output_pieces.h"

#include <cstdio>
#include <deque>
#include <filesystem>
#include <sstream>

#include "runtime/mesh/mesh.h"
#include "runtime/mesh/vtu_writer.h"

namespace simit::scene {

namespace {

// One line per value; lists as a count, then their items.
void put(std::ostringstream& out, const std::string& line) { out << line << '\n'; }

std::string take(std::istringstream& in) {
  std::string line;
  std::getline(in, line);
  return line;
}

// A field of `set`'s first `count` elements as a VTK array (float32 and bool values copied
// into double and int32 arrays kept in `store`).
runtime::VtuArray field_array(const runtime::Set& set, const std::string& name, size_t count,
                              std::deque<std::vector<double>>& doubles,
                              std::deque<std::vector<int32_t>>& ints) {
  const runtime::Field& f = set.field(name);
  const runtime::FieldType& t = f.type();
  const size_t n = count * t.components();
  runtime::VtuArray a{name, static_cast<int>(t.components()), std::span<const double>()};
  if (t.kind == runtime::ComponentKind::Float && !t.single) {
    a.values = std::span<const double>(f.data<double>(), n);
  } else if (t.kind == runtime::ComponentKind::Float) {
    const float* p = f.data<float>();
    a.values = std::span<const double>(doubles.emplace_back(p, p + n));
  } else if (t.kind == runtime::ComponentKind::Int) {
    a.values = std::span<const int32_t>(f.data<int32_t>(), n);
  } else if (t.kind == runtime::ComponentKind::Bool) {
    const bool* p = f.data<bool>();
    a.values = std::span<const int32_t>(ints.emplace_back(p, p + n));
  }
  return a;
}

}  // namespace

std::string PieceSeries::encode(const Settings& s) {
  std::ostringstream out;
  for (const std::string& line : {s.folder, s.name, s.points, s.position, s.cells}) put(out, line);
  for (const auto* list : {&s.point_fields, &s.cell_fields}) {
    put(out, std::to_string(list->size()));
    for (const std::string& f : *list) put(out, f);
  }
  put(out, std::to_string(s.every));
  return out.str();
}

PieceSeries::Settings PieceSeries::decode(const std::string& text) {
  std::istringstream in(text);
  Settings s;
  for (std::string* line : {&s.folder, &s.name, &s.points, &s.position, &s.cells}) *line = take(in);
  for (auto* list : {&s.point_fields, &s.cell_fields}) {
    const int n = std::stoi(take(in));
    for (int i = 0; i < n; ++i) list->push_back(take(in));
  }
  s.every = std::stoi(take(in));
  return s;
}

std::string PieceSeries::piece_file(const std::string& name, int index, int rank) {
  char number[32];
  std::snprintf(number, sizeof number, "_%06d_p%d.vtu", index, rank);
  return name + number;
}

void PieceSeries::write() {
  runtime::Mesh mesh;
  const size_t points = static_cast<size_t>(points_.size());
  if (!settings_.position.empty()) {
    const runtime::Field& x = points_.field(settings_.position);
    mesh.points.resize(points);
    for (size_t p = 0; p < points; ++p)
      for (int d = 0; d < 3; ++d)
        mesh.points[p][d] = x.type().single ? x.at<float>(static_cast<int>(p))[d]
                                            : x.at<double>(static_cast<int>(p))[d];
  } else {
    mesh.points.assign(points, runtime::Point{0.0, 0.0, 0.0});
  }
  if (cells_)
    for (int e = 0; e < owned_cells_; ++e) {
      auto v = [&](int k) { return cells_->endpoint(e, k); };
      if (cells_->arity() == 4)
        mesh.tets.push_back({v(0), v(1), v(2), v(3)});
      else if (cells_->arity() == 3)
        mesh.triangles.push_back({v(0), v(1), v(2)});
      else
        mesh.edges.push_back({v(0), v(1)});
    }
  std::deque<std::vector<double>> doubles;
  std::deque<std::vector<int32_t>> ints;
  std::vector<runtime::VtuArray> point_data, cell_data;
  for (const std::string& f : settings_.point_fields)
    point_data.push_back(field_array(points_, f, points, doubles, ints));
  if (cells_)
    for (const std::string& f : settings_.cell_fields)
      cell_data.push_back(
          field_array(*cells_, f, static_cast<size_t>(owned_cells_), doubles, ints));
  const std::string file = piece_file(settings_.name, index_++, rank_);
  runtime::write_vtu((std::filesystem::path(settings_.folder) / file).string(), mesh, point_data,
                     cell_data);
}

}  // namespace simit::scene
