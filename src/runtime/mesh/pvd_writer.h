// Writer of ParaView time series: a .pvd collection listing one .vtu file per frame.
#pragma once

#include <string>
#include <vector>

#include "runtime/mesh/vtu_writer.h"

namespace simit::runtime {

class PvdWriter {
 public:
  // Frames go beside `pvd_path` (DIR/NAME.pvd) as DIR/NAME_000000.vtu, NAME_000001.vtu, ...
  explicit PvdWriter(std::string pvd_path);

  // Writes the next frame's .vtu (see write_vtu), then rewrites the .pvd to list every frame
  // so far, so that an interrupted run still opens in ParaView. Returns the .vtu's path.
  std::string write_frame(double time, const Mesh& mesh, const std::vector<VtuArray>& point_data,
                          const std::vector<VtuArray>& cell_data);

  // Lists a frame written elsewhere (a .pvtu joining the ranks' pieces: `file` relative to
  // the .pvd's folder) and rewrites the .pvd.
  void add_frame(double time, std::string file);
  // The next frame's file name with `extension` (NAME_000007.vtu, or .pvtu), relative to the
  // .pvd's folder.
  std::string next_frame_file(const std::string& extension) const;
  const std::string& folder() const { return folder_; }

  size_t frames() const { return frames_.size(); }
  const std::string& path() const { return pvd_path_; }

 private:
  struct Frame {
    double time;
    std::string file;  // relative to the .pvd's folder
  };
  void write_collection() const;

  std::string pvd_path_;
  std::string folder_;  // with a trailing '/', or empty
  std::string stem_;
  std::vector<Frame> frames_;
};

}  // namespace simit::runtime
