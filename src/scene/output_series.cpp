// Checking [output] and writing a scene's frames, stats, picture and final positions.
#include "scene/output_series.h"

#include <algorithm>
#include <cctype>
#include <deque>
#include <filesystem>
#include <sstream>

#include "runtime/mesh/atomic_file.h"
#include "runtime/mesh/quicklook.h"
#include "scene/vtu_arrays.h"

namespace simit::scene {

namespace fs = std::filesystem;
using runtime::ComponentKind;
using runtime::FieldType;

namespace {

const char* const kTable = "[output]";

// Row r of the output holds element rows[r] of `set`: the set in its mesh's order. Empty for a
// set in that order already.
std::vector<int32_t> mesh_rows(const runtime::Set& set) {
  if (!set.has_mesh_numbers()) return {};
  std::vector<int32_t> rows(static_cast<size_t>(set.size()));
  for (int e = 0; e < set.size(); ++e) rows[set.mesh_number(e)] = e;
  return rows;
}

// The cells in the mesh's order and with the mesh's vertex numbers (`points` numbers them).
void add_cells(const SceneSet& cells, std::span<const int32_t> rows, const runtime::Set& points,
               runtime::Mesh& m) {
  const std::vector<int32_t>& c = cells.connectivity;
  const size_t ne = c.size() / cells.arity;
  for (size_t r = 0; r < ne; ++r) {
    const int32_t* v = c.data() + (rows.empty() ? r : static_cast<size_t>(rows[r])) * cells.arity;
    auto p = [&](int k) { return points.mesh_number(v[k]); };
    if (cells.arity == 4)
      m.tets.push_back({p(0), p(1), p(2), p(3)});
    else if (cells.arity == 3)
      m.triangles.push_back({p(0), p(1), p(2)});
    else
      m.edges.push_back({p(0), p(1)});
  }
}

// NAME_000000.vtu, NAME_000001.vtu, ... (six digits or more): the frames of the series NAME.
bool is_frame_file(const std::string& file, const std::string& name) {
  const std::string prefix = name + "_";
  if (file.size() < prefix.size() + 6 + 4 || file.compare(0, prefix.size(), prefix) != 0 ||
      !file.ends_with(".vtu"))
    return false;
  const std::string digits = file.substr(prefix.size(), file.size() - prefix.size() - 4);
  return std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); });
}

// FILE.XXXXXX: the temporary an AtomicFile writes before renaming it onto FILE.
bool is_temporary_of(const std::string& file, const std::string& name) {
  if (file.size() < 8 || file[file.size() - 7] != '.') return false;
  const std::string stem = file.substr(0, file.size() - 7);
  if (stem != name + ".pvd" && !is_frame_file(stem, name)) return false;
  return std::all_of(file.end() - 6, file.end(), [](unsigned char c) { return std::isalnum(c); });
}

// One path for every spelling of a file: two outputs, or an output and an input, are the same
// file when these agree.
std::string canonical(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return ec ? fs::absolute(path, ec).lexically_normal().string() : p.string();
}

// The files a run reads: the scene, the program and the mesh files (a TetGen mesh is the whole
// BASE.node/.ele/.face/.edge family).
std::vector<std::pair<std::string, std::string>> run_inputs(const SceneFile& file,
                                                            const BoundSets& sets) {
  std::vector<std::pair<std::string, std::string>> inputs = {{file.path, "the scene file"},
                                                             {file.program_path, "the program"}};
  for (const auto& s : sets.sets) {
    fs::path mesh(s->mesh_path);
    const std::string ext = mesh.extension().string();
    if (ext == ".node" || ext == ".ele" || ext == ".face" || ext == ".edge") {
      for (const char* e : {".node", ".ele", ".face", ".edge"})
        inputs.push_back({fs::path(mesh).replace_extension(e).string(), "a mesh file of the run"});
    } else {
      inputs.push_back({s->mesh_path, "a mesh file of the run"});
    }
  }
  return inputs;
}

}  // namespace

SceneSet* OutputSeries::find_set(const toml::table& t, const BoundSets& sets,
                                 const std::string& key, const std::string& name) const {
  auto it = sets.by_name.find(name);
  if (it == sets.by_name.end())
    file_.fail(t.get(key), std::string(kTable) + " " + key + ": no set '" + name + "' in [sets]");
  return it->second;
}

void OutputSeries::configure(const BoundSets& sets) {
  const toml::node* node = file_.doc.get("output");
  if (!node && !options_.png.empty())
    file_.fail(nullptr, "--png needs an [output] table (its points are what the picture shows)");
  if (!node && !options_.final_csv.empty())
    file_.fail(nullptr, "--final-csv needs [output] points and position");
  if (!node) return;  // no output: run the frames only
  const toml::table* t = node->as_table();
  if (!t) file_.fail(node, "output: expected a table");
  file_.check_keys(*t, kTable,
                   {"folder", "name", "points", "position", "cells", "point_fields", "cell_fields",
                    "every", "csv", "png", "background"});
  folder_ = options_.output_dir.empty() ? file_.required_string(*t, kTable, "folder")
                                        : options_.output_dir;
  file_.required_string(*t, kTable, "name");
  name_ = plain_name(*t, "name");
  const std::string points = file_.required_string(*t, kTable, "points");
  points_ = find_set(*t, sets, "points", points);
  if (points_->elements != Elements::Vertices)
    file_.fail(t->get("points"),
               std::string(kTable) + " points: '" + points + "' is not bound to vertices");
  check_position(*t);
  check_cells(*t, sets);
  field_list(*t, "point_fields", points_, point_fields_);
  field_list(*t, "cell_fields", cells_, cell_fields_);
  if (const toml::node* n = t->get("every")) {
    if (!n->is_integer() || *n->value<int64_t>() < 1)
      file_.fail(n, std::string(kTable) + " every: expected a whole number >= 1");
    every_ = static_cast<int>(*n->value<int64_t>());
  }
  if (const toml::node* n = t->get("background")) {
    if (!n->is_boolean())
      file_.fail(n, std::string(kTable) + " background: expected true or false");
    background_wanted_ = *n->value<bool>();
  }
  if (t->get("csv")) {
    csv_name_ = plain_name(*t, "csv");
    csv_path_ = (fs::path(folder_) / csv_name_).string();
  }
  check_png(*t);
  check_final_csv();
  check_collisions(*t, sets);
  // What a user sees is in the mesh's order, whatever order the sets run in.
  point_rows_ = mesh_rows(*points_->set);
  if (cells_) {
    cell_rows_ = mesh_rows(*cells_->set);
    add_cells(*cells_, cell_rows_, *points_->set, frame_);
  }
}

// A name from [output] (name, csv, png) that stays directly inside the output folder.
std::string OutputSeries::plain_name(const toml::table& t, const std::string& key) const {
  const std::string value = file_.optional_string(t, kTable, key).value_or("");
  const std::string what = std::string(kTable) + " " + key + ": ";
  if (value.empty()) file_.fail(t.get(key), what + "expected a file name, not an empty string");
  if (value.find('/') != std::string::npos || value == "." || value == "..")
    file_.fail(t.get(key), what + "'" + value +
                               "' is not a plain file name (output files go directly in the "
                               "output folder: no '/', no '..')");
  if (std::any_of(value.begin(), value.end(),
                  [](unsigned char c) { return c < 0x20 || c == 0x7f; }))
    file_.fail(t.get(key), what + "the name contains a control character");
  return value;
}

// No two outputs are one file (a CSV named like the .pvd or a frame would be overwritten by
// it), and no output is an input of the run.
void OutputSeries::check_collisions(const toml::table& t, const BoundSets& sets) const {
  struct Output {
    std::string path, key;
    const toml::node* at;
  };
  const bool cli_png = !options_.png.empty();
  std::vector<Output> outputs = {{(fs::path(folder_) / (name_ + ".pvd")).string(),
                                  std::string(kTable) + " name", t.get("name")}};
  if (!csv_path_.empty())
    outputs.push_back({csv_path_, std::string(kTable) + " csv", t.get("csv")});
  if (!png_path_.empty())
    outputs.push_back({png_path_, cli_png ? "--png" : std::string(kTable) + " png",
                       cli_png ? nullptr : t.get("png")});
  if (!options_.final_csv.empty()) outputs.push_back({options_.final_csv, "--final-csv", nullptr});
  const std::string folder = canonical((fs::path(folder_) / "x").string());
  const std::vector<std::pair<std::string, std::string>> inputs = run_inputs(file_, sets);
  for (size_t i = 0; i < outputs.size(); ++i) {
    const Output& o = outputs[i];
    const std::string path = canonical(o.path);
    for (size_t j = 0; j < i; ++j)
      if (canonical(outputs[j].path) == path)
        file_.fail(o.at, o.key + ": '" + o.path + "' is also the file of " + outputs[j].key);
    if (i > 0 && fs::path(path).parent_path() == fs::path(folder).parent_path() &&
        is_frame_file(fs::path(path).filename().string(), name_))
      file_.fail(o.at, o.key + ": '" + o.path + "' is also the name of a frame of the series '" +
                           name_ + "' (" + name_ + "_NNNNNN.vtu)");
    for (const auto& [input, what] : inputs)
      if (canonical(input) == path)
        file_.fail(o.at, o.key + ": '" + o.path + "' is " + what +
                             ": an output must not overwrite an input of the run");
  }
}

// --final-csv (relative to the current folder) needs the positions and a folder to go in.
void OutputSeries::check_final_csv() const {
  if (options_.final_csv.empty()) return;
  if (!points_ || position_field_.empty())
    file_.fail(nullptr, "--final-csv needs [output] points and position");
  const fs::path path(options_.final_csv);
  std::error_code ec;
  if (fs::is_directory(path, ec))
    file_.fail(nullptr, "--final-csv: '" + options_.final_csv + "' is a folder");
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::is_directory(folder, ec) &&
      canonical((folder / "x").string()) != canonical((fs::path(folder_) / "x").string()))
    file_.fail(nullptr, "--final-csv: the folder '" + folder.string() + "' does not exist");
}

// Creates the temporary of --final-csv and removes it again: a folder that refuses the file
// is reported before the first frame.
void OutputSeries::probe_final_csv() const {
  try {
    runtime::AtomicFile probe(options_.final_csv);
  } catch (const runtime::MeshError& e) {
    file_.fail(nullptr, std::string("--final-csv: cannot write: ") + e.what());
  }
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
    file_.fail(t.get("position"),
               tname + " position: '" + position_field_ + "' is " + ft.str() + ", not 3 floats");
}

void OutputSeries::check_cells(const toml::table& t, const BoundSets& sets) {
  auto cells = file_.optional_string(t, kTable, "cells");
  if (!cells) return;
  const std::string tname = kTable;
  cells_ = find_set(t, sets, "cells", *cells);
  if (cells_->elements == Elements::Vertices || cells_->elements == Elements::Hinges)
    file_.fail(t.get("cells"), tname + " cells: '" + *cells + "' must be tets, triangles or edges");
  if (cells_->mesh_path != points_->mesh_path)
    file_.fail(t.get("cells"),
               tname + " cells: '" + *cells + "' is not on the mesh of '" + points_->name + "'");
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

// [output] png (a plain name in the output folder) or --png (relative to the current folder,
// in a folder that exists): a .png name.
void OutputSeries::check_png(const toml::table& t) {
  const bool cli = !options_.png.empty();
  const toml::node* at = cli ? nullptr : t.get("png");
  const std::string key = cli ? "--png" : "[output] png";
  if (cli)
    png_path_ = options_.png;
  else if (t.get("png"))
    png_path_ = (fs::path(folder_) / plain_name(t, "png")).string();
  else
    return;
  const fs::path path(png_path_);
  if (path.extension() != ".png")
    file_.fail(at, key + ": '" + png_path_ + "' is not a .png file name");
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
  // Before the folder where it can be (a failure then leaves nothing); after it when it goes
  // into the output folder.
  std::error_code ec;
  const bool final_csv_first = !options_.final_csv.empty() &&
                               fs::is_directory(fs::absolute(options_.final_csv).parent_path(), ec);
  if (final_csv_first) probe_final_csv();
  fs::create_directories(folder_, ec);
  if (ec)
    file_.fail(t.get("folder"),
               "[output] folder: cannot create '" + folder_ + "': " + ec.message());
  if (!options_.final_csv.empty() && !final_csv_first) probe_final_csv();
  remove_stale_temporaries();
  pvd_ = std::make_unique<runtime::PvdWriter>((fs::path(folder_) / (name_ + ".pvd")).string());
  open_png(t);
  if (csv_path_.empty()) return;
  csv_.open(csv_path_);
  if (!csv_) file_.fail(t.get("csv"), "[output] csv: cannot write '" + csv_path_ + "'");
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

// A run killed before it could remove its temporaries (SIGKILL, a power cut) leaves
// NAME.pvd.XXXXXX or NAME_NNNNNN.vtu.XXXXXX behind; the next run of the series removes them.
void OutputSeries::remove_stale_temporaries() const {
  std::error_code ec;
  std::vector<fs::path> stale;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder_, ec))
    if (entry.is_regular_file(ec) && is_temporary_of(entry.path().filename().string(), name_))
      stale.push_back(entry.path());
  for (const fs::path& p : stale) fs::remove(p, ec);
}

void OutputSeries::write_frame(const MeshCache& meshes, int frame, bool last) {
  if (!pvd_) return;
  const runtime::Set& ps = *points_->set;
  std::vector<runtime::Point> points;
  if (position_field_.empty()) {
    points = meshes.at(points_->mesh_path).points;  // the mesh's order already
  } else {
    const runtime::Field& f = ps.field(position_field_);
    points.resize(static_cast<size_t>(ps.size()));
    for (int r = 0; r < ps.size(); ++r)
      for (int d = 0; d < 3; ++d)
        points[static_cast<size_t>(r)][d] = coordinate(f, row(point_rows_, r), d);
  }
  // A frame written in the background owns copies of the fields: the next frame changes them.
  const bool later = background_ && !last && pieces_ == 0;
  auto store = std::make_shared<ArrayStore>();
  std::vector<runtime::VtuArray> point_data, cell_data;
  for (const std::string& f : point_fields_)
    point_data.push_back(store->add(ps, f, point_rows_, -1, later));
  if (cells_)
    for (const std::string& f : cell_fields_)
      cell_data.push_back(store->add(*cells_->set, f, cell_rows_, -1, later));
  const double time = frame * file_.frame_time;
  if (later) {
    writer_.post([this, time, points = std::move(points), store, point_data, cell_data]() mutable {
      frame_.points = std::move(points);
      pvd_->write_frame(time, frame_, point_data, cell_data);
    });
    return;
  }
  writer_.wait();
  frame_.points = std::move(points);
  if (pieces_ > 0) {
    // The ranks wrote their pieces of this frame: the .pvtu joins them.
    const std::string file = pvd_->next_frame_file(".pvtu");
    const int index = static_cast<int>(pvd_->frames());
    std::vector<std::string> pieces;
    for (int r = 0; r < pieces_; ++r) pieces.push_back(PieceSeries::piece_file(name_, index, r));
    runtime::write_pvtu(pvd_->folder() + file, pieces, point_data, cell_data);
    pvd_->add_frame(time, file);
  } else {
    pvd_->write_frame(time, frame_, point_data, cell_data);
  }
  if (last) write_picture();
}

void OutputSeries::finish_writing_quietly() {
  try {
    writer_.wait();
  } catch (...) {  // NOLINT(bugprone-empty-catch): the run reports the error it stops on
  }
}

PieceSeries::Settings OutputSeries::piece_settings() const {
  PieceSeries::Settings s;
  s.folder = folder_;
  s.name = name_;
  s.points = points_ ? points_->name : "";
  s.position = position_field_;
  s.cells = cells_ ? cells_->name : "";
  s.point_fields = point_fields_;
  s.cell_fields = cell_fields_;
  s.every = every_;
  return s;
}

void OutputSeries::write_picture() {
  writer_.wait();  // frame_ is the writer's until then
  std::string png_error;
  if (pvd_ && !png_path_.empty() && !runtime::write_quicklook(frame_, png_path_, png_error))
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
  if (options_.final_csv.empty() || !points_ || position_field_.empty()) return;
  std::ostringstream out;
  out.precision(17);
  out << "x,y,z\n";
  const runtime::Field& f = points_->set->field(position_field_);
  for (int r = 0; r < points_->set->size(); ++r) {
    for (int d = 0; d < 3; ++d) out << (d ? "," : "") << coordinate(f, row(point_rows_, r), d);
    out << '\n';
  }
  runtime::AtomicFile file(options_.final_csv);
  file.write(out.str());
  file.commit();
}

}  // namespace simit::scene
