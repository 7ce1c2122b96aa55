// Checking [output] and writing a scene's frames, stats, picture and final positions.
#include "scene/output_series.h"

#include <deque>
#include <filesystem>

#include "runtime/mesh/atomic_file.h"
#include "runtime/mesh/quicklook.h"

namespace simit::scene {

namespace fs = std::filesystem;
using runtime::ComponentKind;
using runtime::FieldType;

namespace {

const char* const kTable = "[output]";

// Field values of a set as a VTK array (converted to double or int32 where needed).
struct ArrayStore {
  std::deque<std::vector<double>> doubles;
  std::deque<std::vector<int32_t>> ints;
  runtime::VtuArray add(const runtime::Set& set, const std::string& name) {
    const runtime::Field& f = set.field(name);
    const FieldType& ft = f.type();
    const size_t count = ft.components() * static_cast<size_t>(set.size());
    runtime::VtuArray a{name, static_cast<int>(ft.components()), std::span<const double>()};
    switch (ft.kind) {
      case ComponentKind::Float:
        if (!ft.single) {
          a.values = std::span<const double>(f.data<double>(), count);
        } else {
          const float* p = f.data<float>();
          doubles.emplace_back(p, p + count);
          a.values = std::span<const double>(doubles.back());
        }
        break;
      case ComponentKind::Int: a.values = std::span<const int32_t>(f.data<int32_t>(), count); break;
      case ComponentKind::Bool: {
        const bool* p = f.data<bool>();
        ints.emplace_back(p, p + count);
        a.values = std::span<const int32_t>(ints.back());
        break;
      }
      default: break;
    }
    return a;
  }
};

double coordinate(const runtime::Field& f, int i, int d) {
  return f.type().single ? f.at<float>(i)[d] : f.at<double>(i)[d];
}

void add_cells(const SceneSet& cells, runtime::Mesh& m) {
  const std::vector<int32_t>& c = cells.connectivity;
  const size_t ne = c.size() / cells.arity;
  for (size_t e = 0; e < ne; ++e) {
    const int32_t* v = c.data() + e * cells.arity;
    if (cells.arity == 4) m.tets.push_back({v[0], v[1], v[2], v[3]});
    else if (cells.arity == 3) m.triangles.push_back({v[0], v[1], v[2]});
    else m.edges.push_back({v[0], v[1]});
  }
}

}  // namespace

SceneSet* OutputSeries::find_set(const toml::table& t, const BoundSets& sets, const std::string& key,
                                 const std::string& name) const {
  auto it = sets.by_name.find(name);
  if (it == sets.by_name.end())
    file_.fail(t.get(key), std::string(kTable) + " " + key + ": no set '" + name + "' in [sets]");
  return it->second;
}

void OutputSeries::configure(const BoundSets& sets) {
  const toml::node* node = file_.doc.get("output");
  if (!node && !options_.png.empty())
    file_.fail(nullptr, "--png needs an [output] table (its points are what the picture shows)");
  if (!node) return;  // no output: run the frames only
  const toml::table* t = node->as_table();
  if (!t) file_.fail(node, "output: expected a table");
  file_.check_keys(*t, kTable, {"folder", "name", "points", "position", "cells", "point_fields",
                                "cell_fields", "every", "csv", "png"});
  folder_ = options_.output_dir.empty() ? file_.required_string(*t, kTable, "folder") : options_.output_dir;
  name_ = file_.required_string(*t, kTable, "name");
  const std::string points = file_.required_string(*t, kTable, "points");
  points_ = find_set(*t, sets, "points", points);
  if (points_->elements != Elements::Vertices)
    file_.fail(t->get("points"), std::string(kTable) + " points: '" + points + "' is not bound to vertices");
  check_position(*t);
  check_cells(*t, sets);
  field_list(*t, "point_fields", points_, point_fields_);
  field_list(*t, "cell_fields", cells_, cell_fields_);
  if (const toml::node* n = t->get("every")) {
    if (!n->is_integer() || *n->value<int64_t>() < 1)
      file_.fail(n, std::string(kTable) + " every: expected a whole number >= 1");
    every_ = static_cast<int>(*n->value<int64_t>());
  }
  if (auto csv = file_.optional_string(*t, kTable, "csv")) csv_path_ = (fs::path(folder_) / *csv).string();
  check_png(*t);
}

void OutputSeries::check_position(const toml::table& t) {
  position_field_ = file_.optional_string(t, kTable, "position").value_or("");
  if (position_field_.empty()) return;
  const std::string tname = kTable;
  if (points_->set->field_index(position_field_) < 0)
    file_.fail(t.get("position"), tname + " position: set '" + points_->name + "' has no field '" +
                                      position_field_ + "'");
  const FieldType& ft = points_->set->field(position_field_).type();
  if (ft.kind != ComponentKind::Float || ft.components() != 3)
    file_.fail(t.get("position"), tname + " position: '" + position_field_ + "' is " + ft.str() +
                                      ", not 3 floats");
}

void OutputSeries::check_cells(const toml::table& t, const BoundSets& sets) {
  auto cells = file_.optional_string(t, kTable, "cells");
  if (!cells) return;
  const std::string tname = kTable;
  cells_ = find_set(t, sets, "cells", *cells);
  if (cells_->elements == Elements::Vertices || cells_->elements == Elements::Hinges)
    file_.fail(t.get("cells"), tname + " cells: '" + *cells + "' must be tets, triangles or edges");
  if (cells_->mesh_path != points_->mesh_path)
    file_.fail(t.get("cells"), tname + " cells: '" + *cells + "' is not on the mesh of '" +
                                   points_->name + "'");
}

void OutputSeries::field_list(const toml::table& t, const std::string& key, const SceneSet* s,
                              std::vector<std::string>& list) const {
  const toml::node* n = t.get(key);
  if (!n) return;
  const std::string tname = kTable;
  const toml::array* a = n->as_array();
  if (!a) file_.fail(n, tname + " " + key + ": expected an array of field names");
  if (!s) file_.fail(n, tname + " " + key + ": needs 'cells'");
  for (const toml::node& item : *a) {
    if (!item.is_string()) file_.fail(&item, tname + " " + key + ": expected field names");
    std::string f = *item.value<std::string>();
    if (s->set->field_index(f) < 0)
      file_.fail(&item, tname + " " + key + ": set '" + s->name + "' has no field '" + f + "'");
    if (s->set->field(f).type().kind == ComponentKind::Complex)
      file_.fail(&item, tname + " " + key + ": complex field '" + f + "' cannot be written");
    list.push_back(f);
  }
}

// [output] png (relative to the output folder) or --png (relative to the current folder): a
// .png name in the output folder or in a folder that exists.
void OutputSeries::check_png(const toml::table& t) {
  const std::optional<std::string> key_value = file_.optional_string(t, kTable, "png");
  const bool cli = !options_.png.empty();
  const toml::node* at = cli ? nullptr : t.get("png");
  const std::string key = cli ? "--png" : "[output] png";
  if (cli) png_path_ = options_.png;
  else if (key_value) png_path_ = (fs::path(folder_) / *key_value).string();
  else return;
  const fs::path path(png_path_);
  if (path.extension() != ".png") file_.fail(at, key + ": '" + png_path_ + "' is not a .png file name");
  std::error_code ec;
  if (fs::is_directory(path, ec)) file_.fail(at, key + ": '" + png_path_ + "' is a folder");
  const fs::path folder = (path.parent_path().empty() ? fs::path(".") : path.parent_path());
  const fs::path out = (fs::path(folder_) / "x").parent_path();
  if (folder.lexically_normal() != out.lexically_normal() && !fs::is_directory(folder, ec))
    file_.fail(at, key + ": the folder '" + folder.string() + "' does not exist");
}

void OutputSeries::open(const std::vector<std::string>& stats) {
  if (!points_) return;
  const toml::table& t = *file_.doc["output"].as_table();
  std::error_code ec;
  fs::create_directories(folder_, ec);
  if (ec)
    file_.fail(t.get("folder"), "[output] folder: cannot create '" + folder_ + "': " + ec.message());
  pvd_ = std::make_unique<runtime::PvdWriter>((fs::path(folder_) / (name_ + ".pvd")).string());
  open_png(t);
  if (csv_path_.empty()) return;
  csv_.open(csv_path_);
  if (!csv_) throw SceneError(file_.path + ": error: [output] csv: cannot write '" + csv_path_ + "'");
  csv_.precision(17);
  csv_ << "frame,time,ms";
  for (const std::string& s : stats) csv_ << ',' << s;
  // Last, so the columns before them keep their places: the frame's time in outermost
  // map/apply assemblies, and the rest of it (mostly the CG solve).
  csv_ << ",assembly_ms,solve_ms\n";
}

// Makes sure the quick-look picture can be written before any frame runs.
void OutputSeries::open_png(const toml::table& t) {
  if (png_path_.empty()) return;
  try {
    runtime::AtomicFile probe(png_path_);  // removed again: only a test that the folder takes it
  } catch (const runtime::MeshError& e) {
    const bool cli = !options_.png.empty();
    file_.fail(cli ? nullptr : t.get("png"),
               std::string(cli ? "--png" : "[output] png") + ": cannot write: " + e.what());
  }
}

void OutputSeries::write_frame(const MeshCache& meshes, int frame, bool last) {
  if (!pvd_) return;
  runtime::Mesh m;
  const runtime::Set& ps = *points_->set;
  if (position_field_.empty()) {
    m.points = meshes.at(points_->mesh_path).points;
  } else {
    const runtime::Field& f = ps.field(position_field_);
    m.points.resize(ps.size());
    for (int i = 0; i < ps.size(); ++i)
      for (int d = 0; d < 3; ++d) m.points[i][d] = coordinate(f, i, d);
  }
  if (cells_) add_cells(*cells_, m);
  ArrayStore store;
  std::vector<runtime::VtuArray> point_data, cell_data;
  for (const std::string& f : point_fields_) point_data.push_back(store.add(ps, f));
  if (cells_)
    for (const std::string& f : cell_fields_) cell_data.push_back(store.add(*cells_->set, f));
  pvd_->write_frame(frame * file_.frame_time, m, point_data, cell_data);
  std::string png_error;
  if (last && !png_path_.empty() && !runtime::write_quicklook(m, png_path_, png_error))
    throw SceneError(file_.path + ": error: writing the quick-look picture: " + png_error);
}

void OutputSeries::write_stats(int frame, double ms, const std::vector<double>& stats,
                               double assembly_ms) {
  if (!csv_.is_open()) return;
  csv_ << frame << ',' << frame * file_.frame_time << ',' << ms;
  for (double s : stats) csv_ << ',' << s;
  csv_ << ',' << assembly_ms << ',' << ms - assembly_ms;
  csv_ << '\n' << std::flush;
}

void OutputSeries::write_final_csv() const {
  if (options_.final_csv.empty()) return;
  std::ofstream out(options_.final_csv);
  out.precision(17);
  out << "x,y,z\n";
  if (!points_ || position_field_.empty())
    throw SceneError(file_.path + ": error: --final-csv needs [output] points and position");
  const runtime::Field& f = points_->set->field(position_field_);
  for (int i = 0; i < points_->set->size(); ++i) {
    for (int d = 0; d < 3; ++d) out << (d ? "," : "") << coordinate(f, i, d);
    out << '\n';
  }
  if (!out) throw SceneError(options_.final_csv + ": error: cannot write");
}

}  // namespace simit::scene
