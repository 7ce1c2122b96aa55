// A quick-look picture of a mesh: a small software rendering of its surface (or lines, or
// points) from a fixed three-quarter view, for a glance at a simulation's last frame.
#pragma once

#include <string>

#include "runtime/image.h"
#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// The view: orthographic, looking along -(1, 1, 1) (from the +x, +y, +z side), with y up on
// the picture. A point p appears at screen coordinates u = p . kRight, v = p . kUp (v grows
// upwards) and depth p . (-1, -1, -1) / sqrt(3).
struct QuicklookView {
  static constexpr double kRight[3] = {0.70710678118654752, 0.0, -0.70710678118654752};
  static constexpr double kUp[3] = {-0.40824829046386302, 0.81649658092772603,
                                    -0.40824829046386302};
};

struct QuicklookOptions {
  int width = 480;
  int height = 360;
  int margin = 12;  // pixels left free around the fitted mesh
};

// Renders `mesh` fitted to the picture: the projected bounding box of its finite points is
// scaled uniformly to fill the picture less the margin, and centred. Draws what the mesh has,
// in this order of preference: the boundary triangles of its tets, its triangles (shaded on
// both sides), its edges as lines, else its points. Lambert shading with a little ambient
// light on a white-ish background; elements with a non-finite point are left out. Vertex
// indices must be in range (check_indices).
Image render_quicklook(const Mesh& mesh, const QuicklookOptions& options = {});

// render_quicklook, then write_png to `path` (atomically). Returns false with `error` set
// when the picture cannot be written (or when the tets' boundary cannot be found).
bool write_quicklook(const Mesh& mesh, const std::string& path, std::string& error,
                     const QuicklookOptions& options = {});

}  // namespace simit::runtime
