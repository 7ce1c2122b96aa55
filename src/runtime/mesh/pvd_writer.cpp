// .pvd collections: the frame list is small, so it is rewritten whole after every frame.
#include "runtime/mesh/pvd_writer.h"

#include <bit>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "runtime/mesh/atomic_file.h"

namespace simit::runtime {

namespace {

// Shortest text that reads back as the same double, so ParaView's times are exact.
std::string exact(double value) {
  char text[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

}  // namespace

PvdWriter::PvdWriter(std::string pvd_path) : pvd_path_(std::move(pvd_path)) {
  size_t slash = pvd_path_.find_last_of('/');
  folder_ = slash == std::string::npos ? "" : pvd_path_.substr(0, slash + 1);
  stem_ = pvd_path_.substr(folder_.size());
  if (stem_.size() > 4 && stem_.ends_with(".pvd")) stem_.resize(stem_.size() - 4);
}

std::string PvdWriter::write_frame(double time, const Mesh& mesh,
                                   const std::vector<VtuArray>& point_data,
                                   const std::vector<VtuArray>& cell_data) {
  std::string file = next_frame_file(".vtu");
  write_vtu(folder_ + file, mesh, point_data, cell_data);
  add_frame(time, file);
  return folder_ + file;
}

std::string PvdWriter::next_frame_file(const std::string& extension) const {
  char number[16];
  std::snprintf(number, sizeof number, "_%06zu", frames_.size());
  return stem_ + number + extension;
}

void PvdWriter::add_frame(double time, std::string file) {
  frames_.push_back({time, std::move(file)});
  write_collection();
}

void PvdWriter::write_collection() const {
  // ParaView's writers state the byte order even in files that hold no binary data.
  const char* byte_order =
      std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"" << byte_order << "\">\n"
      << "  <Collection>\n";
  for (const Frame& f : frames_)
    xml << "    <DataSet timestep=\"" << exact(f.time) << "\" group=\"\" part=\"0\" file=\""
        << xml_escape(f.file) << "\"/>\n";
  xml << "  </Collection>\n</VTKFile>\n";
  AtomicFile out(pvd_path_);
  out.write(xml.str());
  out.commit();
}

}  // namespace simit::runtime
