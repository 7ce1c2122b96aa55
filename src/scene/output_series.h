// [output]: what a scene writes and where: a ParaView series (.pvd + one .vtu per written
// frame), a per-frame CSV of timings and step results, a quick-look PNG of the last frame,
// and (--final-csv) the last positions. Everything is checked before the first frame; the
// folder is created only once every check has passed. The names in [output] are plain file
// names inside the output folder, distinct from each other and from the run's inputs.
#pragma once

#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/mesh/pvd_writer.h"
#include "scene/frame_writer.h"
#include "scene/mesh_binding.h"
#include "scene/mesh_cache.h"
#include "scene/output_pieces.h"
#include "scene/scene_file.h"
#include "simit/scene.h"

namespace simit::scene {

class OutputSeries {
 public:
  OutputSeries(const SceneFile& file, const SceneOptions& options)
      : file_(file), options_(options) {}

  // Checks [output] (and --output, --png) against the built sets. Throws SceneError.
  void configure(const BoundSets& sets);
  // Creates the folder, the .pvd and the stats CSV (its header: frame, time, ms, `stats`,
  // assembly_ms, solve_ms) and makes sure the picture can be written. Throws SceneError.
  void open(const std::vector<std::string>& stats);

  // Writes frame `frame` (0: the state after init) at time frame * frame_time; the picture
  // too when it is `last`. In the background (below), a frame that is not the last is copied
  // and handed to the writer thread; an error of the frame written before it throws here.
  void write_frame(const MeshCache& meshes, int frame, bool last);
  // Frames other than the last are written on a thread of their own (scene/frame_writer.h)
  // while the next frame computes.
  // [output] background = true or false decides; without it, `spare_core`: whether the run
  // leaves a core free.
  void write_in_background(bool spare_core) {
    background_ = background_wanted_.value_or(spare_core);
  }
  // Waits until the frames handed to the writer are written; throws the first error.
  void finish_writing() { writer_.wait(); }
  // The same, for a run that is stopping on another error: a write error is dropped.
  void finish_writing_quietly();
  // The picture of the frame written last, when one is asked for (a run that did not know
  // which frame would be its last when it wrote it).
  void write_picture();
  // One row of the stats CSV, when there is one.
  void write_stats(int frame, double ms, const std::vector<double>& stats, double assembly_ms);
  // --final-csv: the last frame's positions as x,y,z lines (under a temporary name, renamed
  // when complete).
  void write_final_csv() const;

  bool every_frame(int frame) const { return frame % every_ == 0; }
  // A distributed run on `ranks` ranks: each frame becomes a .pvtu joining the ranks' pieces
  // (scene/output_pieces.h), which they write before write_frame; what the pieces hold is
  // piece_settings(). Only once open() made the series (writes_frames()).
  bool writes_frames() const { return pvd_ != nullptr; }
  PieceSeries::Settings piece_settings() const;
  void join_pieces(int ranks) { pieces_ = ranks; }
  // The .pvd written, or empty when nothing is.
  std::string pvd_path() const { return pvd_ ? pvd_->path() : std::string(); }

 private:
  SceneSet* find_set(const toml::table& t, const BoundSets& sets, const std::string& key,
                     const std::string& name) const;
  void check_position(const toml::table& t);
  void check_cells(const toml::table& t, const BoundSets& sets);
  void field_list(const toml::table& t, const std::string& key, const SceneSet* s,
                  std::vector<std::string>& list) const;
  void check_png(const toml::table& t);
  std::string plain_name(const toml::table& t, const std::string& key) const;
  void check_collisions(const toml::table& t, const BoundSets& sets) const;
  void check_final_csv() const;
  void probe_final_csv() const;
  void open_png(const toml::table& t);
  void remove_stale_temporaries() const;

  const SceneFile& file_;
  const SceneOptions& options_;
  std::string folder_, name_, csv_name_, csv_path_;
  std::string png_path_;  // the quick-look picture of the last frame, when asked for
  SceneSet* points_ = nullptr;
  SceneSet* cells_ = nullptr;
  std::string position_field_;
  std::vector<std::string> point_fields_, cell_fields_;
  // Row r of the output is element rows[r] of the set (empty: element r): the mesh's order.
  static int row(const std::vector<int32_t>& rows, int r) { return rows.empty() ? r : rows[r]; }
  std::vector<int32_t> point_rows_, cell_rows_;
  runtime::Mesh frame_;  // the cells (the mesh's order and numbers), the points of each frame
  int every_ = 1;
  std::unique_ptr<runtime::PvdWriter> pvd_;
  int pieces_ = 0;  // ranks whose pieces each frame's .pvtu joins; 0: one .vtu a frame
  std::ofstream csv_;
  bool background_ = false;
  std::optional<bool> background_wanted_;  // [output] background
  // Last, so that it is destroyed first: its job may be writing frame_ through pvd_.
  FrameWriter writer_;
};

}  // namespace simit::scene
