// Gmsh .msh reader (https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format): sections
// between $Name and $EndName; version 4.1 groups nodes and elements into entity blocks.
#include "runtime/mesh/gmsh_reader.h"

#include <algorithm>
#include <unordered_map>

#include "runtime/mesh/line_reader.h"

namespace simit::runtime {

namespace {

constexpr int kMaxReserve = 1 << 20;

// Where an element type's corners go; `nodes` counts all its nodes, corners come first.
struct ElementType {
  ElementKind kind;
  int nodes;
};

bool element_type(long long type, ElementType& out) {
  switch (type) {
    case 1: out = {ElementKind::Edge, 2}; return true;
    case 2: out = {ElementKind::Triangle, 3}; return true;
    case 4: out = {ElementKind::Tet, 4}; return true;
    case 8: out = {ElementKind::Edge, 3}; return true;
    case 9: out = {ElementKind::Triangle, 6}; return true;
    case 11: out = {ElementKind::Tet, 10}; return true;
    default: return false;
  }
}

// The header of a 4.1 entity block; `third` is the parametric flag for nodes and the element
// type for elements.
struct BlockHeader {
  int dim;
  long long third;
  int count;
};

class GmshReader {
 public:
  explicit GmshReader(const std::string& path) : in_(path, '\0') {}
  Mesh read();

 private:
  void read_format();
  void read_nodes_v2();
  void read_nodes_v4();
  void read_elements_v2();
  void read_elements_v4();
  BlockHeader read_block_header(const char* third);
  void add_node_tag(size_t token);
  int node(size_t token) const;
  void read_element(long long tag, size_t first, const ElementType& type);
  void next_record(int index, int total, const char* noun);
  void expect_line(const std::string& marker, const std::string& what);
  void expect_end(const char* section, int count, const char* noun);
  void skip_section(const std::string& name);

  LineReader in_;
  Mesh mesh_;
  int version_ = 0;
  bool have_nodes_ = false;
  bool have_elements_ = false;
  std::unordered_map<long long, int> node_index_;
};

Mesh GmshReader::read() {
  in_.require_next("$MeshFormat");
  if (in_[0] != "$MeshFormat") in_.fail_token(0, "$MeshFormat on the first line");
  read_format();
  while (in_.next()) {
    std::string section(in_[0]);
    if (section[0] != '$') in_.fail_token(0, "a section such as $Nodes or $Elements");
    in_.expect_end(1, "a section name");
    if (section == "$Nodes") {
      if (have_nodes_) in_.fail("expected one $Nodes section, found a second");
      version_ == 2 ? read_nodes_v2() : read_nodes_v4();
      have_nodes_ = true;
    } else if (section == "$Elements") {
      if (!have_nodes_) in_.fail("expected the $Nodes section before $Elements");
      if (have_elements_) in_.fail("expected one $Elements section, found a second");
      version_ == 2 ? read_elements_v2() : read_elements_v4();
      have_elements_ = true;
    } else if (section == "$MeshFormat") {
      in_.fail("expected one $MeshFormat section, found a second");
    } else {
      skip_section(section.substr(1));
    }
  }
  if (!have_nodes_) in_.fail("expected a $Nodes section, found end of file");
  return std::move(mesh_);
}

void GmshReader::read_format() {
  in_.require_next("the format line 'version file-type data-size'");
  std::string_view version = in_[0];
  if (version == "4.1") {
    version_ = 4;
  } else if (version == "2" || version.starts_with("2.")) {
    version_ = 2;
  } else {
    in_.fail_token(0, "format version 2.2 or 4.1");
  }
  if (in_.integer(1, "file-type 0 (ASCII; binary .msh files are not supported)") != 0)
    in_.fail_token(1, "file-type 0 (ASCII; binary .msh files are not supported)");
  in_.integer(2, "a data size");
  in_.expect_end(3, "the format line");
  expect_line("$EndMeshFormat", "$EndMeshFormat");
}

void GmshReader::next_record(int index, int total, const char* noun) {
  if (!in_.next())
    in_.fail("expected " + std::to_string(total) + " " + noun +
             " records (the section's count), found end of file after " + std::to_string(index));
  if (in_[0].starts_with("$"))
    in_.fail("expected " + std::to_string(total) + " " + noun +
             " records (the section's count), found " + std::string(in_[0]) + " after " +
             std::to_string(index));
}

void GmshReader::expect_line(const std::string& marker, const std::string& what) {
  in_.require_next(what);
  if (in_[0] != marker) in_.fail_token(0, what);
  in_.expect_end(1, marker);
}

// The end marker of a section whose header announced `count` records.
void GmshReader::expect_end(const char* section, int count, const char* noun) {
  std::string marker = std::string("$End") + section;
  expect_line(marker,
              marker + " after " + std::to_string(count) + " " + noun + " (the section's count)");
}

void GmshReader::skip_section(const std::string& name) {
  std::string end = "$End" + name;
  while (in_.next())
    if (in_[0] == end) return;
  in_.fail("expected " + end + ", found end of file");
}

void GmshReader::add_node_tag(size_t token) {
  long long tag = in_.integer(token, "a node tag");
  int index = static_cast<int>(node_index_.size());
  if (!node_index_.emplace(tag, index).second)
    in_.fail_token(token, "a node tag not used by an earlier node");
  mesh_.point_numbers.ids.push_back(tag);
}

int GmshReader::node(size_t token) const {
  long long tag = in_.integer(token, "a node tag");
  auto it = node_index_.find(tag);
  if (it == node_index_.end()) in_.fail_token(token, "a node tag defined in $Nodes");
  return it->second;
}

void GmshReader::read_nodes_v2() {
  in_.require_next("the node count");
  int n = in_.count(0, "the node count");
  in_.expect_end(1, "the node count");
  mesh_.points.reserve(std::min(n, kMaxReserve));
  for (int i = 0; i < n; ++i) {
    next_record(i, n, "node");
    add_node_tag(0);
    Point p{};
    for (int k = 0; k < 3; ++k) p[k] = in_.number(1 + k, std::string(1, "xyz"[k]) + " coordinate");
    in_.expect_end(4, "a node record");
    mesh_.points.push_back(p);
  }
  expect_end("Nodes", n, "nodes");
}

BlockHeader GmshReader::read_block_header(const char* third) {
  BlockHeader h{};
  h.dim = in_.count(0, "an entity dimension, 0 to 3");
  if (h.dim > 3) in_.fail_token(0, "an entity dimension, 0 to 3");
  in_.integer(1, "an entity tag");
  h.third = in_.integer(2, third);
  h.count = in_.count(3, "the block's record count");
  in_.expect_end(4, "an entity block header");
  return h;
}

void GmshReader::read_nodes_v4() {
  in_.require_next("the header 'block-count node-count min-tag max-tag'");
  int blocks = in_.count(0, "the entity-block count");
  int total = in_.count(1, "the node count");
  in_.integer(2, "the minimum node tag");
  in_.integer(3, "the maximum node tag");
  in_.expect_end(4, "the $Nodes header");
  mesh_.points.reserve(std::min(total, kMaxReserve));
  for (int b = 0; b < blocks; ++b) {
    next_record(b, blocks, "entity-block");
    BlockHeader h = read_block_header("the parametric flag, 0 or 1");
    int m = h.count;
    if (h.third != 0 && h.third != 1) in_.fail_token(2, "the parametric flag, 0 or 1");
    if (m > total - static_cast<int>(mesh_.points.size()))
      in_.fail_token(3, "at most " + std::to_string(total - mesh_.points.size()) +
                            " more nodes (the section's count)");
    for (int j = 0; j < m; ++j) {
      next_record(j, m, "node-tag");
      add_node_tag(0);
      in_.expect_end(1, "a node tag");
    }
    size_t params = h.third ? static_cast<size_t>(h.dim) : 0;
    for (int j = 0; j < m; ++j) {
      next_record(j, m, "node-coordinate");
      Point p{};
      for (int k = 0; k < 3; ++k) p[k] = in_.number(k, std::string(1, "xyz"[k]) + " coordinate");
      for (size_t k = 0; k < params; ++k) in_.number(3 + k, "a parametric coordinate");
      in_.expect_end(3 + params, "a node's coordinates");
      mesh_.points.push_back(p);
    }
  }
  if (static_cast<int>(mesh_.points.size()) != total)
    in_.fail("expected " + std::to_string(total) + " nodes (the header's count), found " +
             std::to_string(mesh_.points.size()));
  expect_end("Nodes", total, "nodes");
}

void GmshReader::read_element(long long tag, size_t first, const ElementType& type) {
  std::array<int, 4> corners{};
  for (int k = 0; k < type.nodes; ++k) {
    int v = node(first + k);
    if (k < 4) corners[k] = v;
  }
  in_.expect_end(first + type.nodes, "an element record");
  switch (type.kind) {
    case ElementKind::Tet:
      mesh_.tets.push_back(corners);
      mesh_.tet_numbers.ids.push_back(tag);
      break;
    case ElementKind::Triangle:
      mesh_.triangles.push_back({corners[0], corners[1], corners[2]});
      mesh_.triangle_numbers.ids.push_back(tag);
      break;
    case ElementKind::Edge:
      mesh_.edges.push_back({corners[0], corners[1]});
      mesh_.edge_numbers.ids.push_back(tag);
      break;
  }
}

void GmshReader::read_elements_v2() {
  in_.require_next("the element count");
  int n = in_.count(0, "the element count");
  in_.expect_end(1, "the element count");
  for (int i = 0; i < n; ++i) {
    next_record(i, n, "element");
    long long tag = in_.integer(0, "an element tag");
    ElementType type{};
    bool used = element_type(in_.integer(1, "an element type"), type);
    int tags = in_.count(2, "the element's tag count");
    if (!used) continue;
    for (int t = 0; t < tags; ++t) in_.integer(3 + t, "an element tag (physical, geometrical)");
    read_element(tag, 3 + static_cast<size_t>(tags), type);
  }
  expect_end("Elements", n, "elements");
}

void GmshReader::read_elements_v4() {
  in_.require_next("the header 'block-count element-count min-tag max-tag'");
  int blocks = in_.count(0, "the entity-block count");
  int total = in_.count(1, "the element count");
  in_.integer(2, "the minimum element tag");
  in_.integer(3, "the maximum element tag");
  in_.expect_end(4, "the $Elements header");
  int seen = 0;
  for (int b = 0; b < blocks; ++b) {
    next_record(b, blocks, "entity-block");
    BlockHeader h = read_block_header("an element type");
    int m = h.count;
    if (m > total - seen)
      in_.fail_token(
          3, "at most " + std::to_string(total - seen) + " more elements (the section's count)");
    ElementType type{};
    bool used = element_type(h.third, type);
    for (int j = 0; j < m; ++j, ++seen) {
      next_record(j, m, "element");
      long long tag = in_.integer(0, "an element tag");
      if (used) read_element(tag, 1, type);
    }
  }
  if (seen != total)
    in_.fail("expected " + std::to_string(total) + " elements (the header's count), found " +
             std::to_string(seen));
  expect_end("Elements", total, "elements");
}

}  // namespace

Mesh read_gmsh(const std::string& path) { return GmshReader(path).read(); }

}  // namespace simit::runtime
