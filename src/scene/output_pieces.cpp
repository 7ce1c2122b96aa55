// A distributed run's pieces of each frame (scene/output_pieces.h).
#include "scene/output_pieces.h"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "runtime/mesh/mesh.h"
#include "runtime/mesh/vtu_writer.h"
#include "scene/vtu_arrays.h"

namespace simit::scene {

namespace {

// One line per value; lists as a count, then their items.
void put(std::ostringstream& out, const std::string& line) { out << line << '\n'; }

std::string take(std::istringstream& in) {
  std::string line;
  std::getline(in, line);
  return line;
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
      for (int d = 0; d < 3; ++d) mesh.points[p][d] = coordinate(x, static_cast<int>(p), d);
  } else {
    mesh.points.assign(points, runtime::Point{0.0, 0.0, 0.0});
  }
  if (cells_)
    for (int32_t e : owned_cells_) {
      auto v = [&](int k) { return cells_->endpoint(e, k); };
      if (cells_->arity() == 4)
        mesh.tets.push_back({v(0), v(1), v(2), v(3)});
      else if (cells_->arity() == 3)
        mesh.triangles.push_back({v(0), v(1), v(2)});
      else
        mesh.edges.push_back({v(0), v(1)});
    }
  ArrayStore store;
  std::vector<runtime::VtuArray> point_data, cell_data;
  for (const std::string& f : settings_.point_fields)
    point_data.push_back(store.add(points_, f, {}));
  if (cells_)
    for (const std::string& f : settings_.cell_fields)
      cell_data.push_back(
          store.add(*cells_, f, owned_cells_, static_cast<int>(owned_cells_.size())));
  const std::string file = piece_file(settings_.name, index_++, rank_);
  runtime::write_vtu((std::filesystem::path(settings_.folder) / file).string(), mesh, point_data,
                     cell_data);
}

}  // namespace simit::scene
