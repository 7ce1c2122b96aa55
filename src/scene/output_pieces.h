// A distributed run's frames as ParaView's parallel files: each rank writes its piece of every
// frame (NAME_NNNNNN_pR.vtu: its points, owned and ghost, and the cells it owns), and rank 0
// writes the NAME_NNNNNN.pvtu that joins them and lists it in NAME.pvd (scene/output_series.h).
#pragma once

#include <string>
#include <vector>

#include "runtime/set.h"

namespace simit::scene {

class PieceSeries {
 public:
  // What rank 0's [output] says the pieces hold, sent to the other ranks as text.
  struct Settings {
    std::string folder, name, points, position, cells;
    std::vector<std::string> point_fields, cell_fields;
    int every = 1;
  };
  static std::string encode(const Settings& s);
  static Settings decode(const std::string& text);
  // Piece `rank` of the series' frame `index` (its number in the .pvd), in the output folder.
  static std::string piece_file(const std::string& name, int index, int rank);

  // `points` and `cells` (null for none): this rank's parts of the sets [output] names, the
  // cells `owned_cells` (local indices, ascending) its own.
  PieceSeries(Settings settings, int rank, const runtime::Set& points, const runtime::Set* cells,
              std::vector<int32_t> owned_cells)
      : settings_(std::move(settings)),
        rank_(rank),
        points_(points),
        cells_(cells),
        owned_cells_(std::move(owned_cells)) {}

  bool every_frame(int frame) const { return frame % settings_.every == 0; }
  // Writes this rank's piece of the next frame (under a temporary name, renamed when complete).
  void write();

 private:
  Settings settings_;
  int rank_;
  const runtime::Set& points_;
  const runtime::Set* cells_;
  std::vector<int32_t> owned_cells_;
  int index_ = 0;  // the next frame's number in the series
};

}  // namespace simit::scene
