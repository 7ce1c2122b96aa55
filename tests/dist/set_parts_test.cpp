// A scene's sets cut into the ranks' parts and sent as messages (dist/set_parts.h): every
// rank's decoded part holds the elements of its overlapping layout, with the whole sets'
// fields, endpoints and mesh numbers, listed in the whole sets' order whatever that order is.
#include "dist/set_parts.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace simit::dist {
namespace {

// A strip of 4 x 2 quads cut into triangles over 15 points, listed edge set first; a float
// field of 3 components and an int field on the points, a float field on the triangles.
struct Strip {
  runtime::Set points{"points"};
  runtime::Set tris{"tris", {&points, &points, &points}};
  Strip() {
    points.add_many(15);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 2; ++j) {
        const int a = i * 3 + j, b = a + 3, c = a + 1, d = b + 1;
        tris.add({a, b, c});
        tris.add({c, b, d});
      }
    points.add_field("x", {runtime::ComponentKind::Float, {3}, false});
    points.add_field("tag", {runtime::ComponentKind::Int, {}, false});
    tris.add_field("area", {runtime::ComponentKind::Float, {}, false});
    for (int p = 0; p < 15; ++p) {
      double* x = points.field("x").at<double>(p);
      x[0] = p, x[1] = 0.5 * p, x[2] = -p;
      *points.field("tag").at<int32_t>(p) = 100 + p;
    }
    for (int t = 0; t < tris.size(); ++t) *tris.field("area").at<double>(t) = 0.25 * t;
    // A renumbered mesh: the mesh numbers run backwards.
    std::vector<int32_t> numbers(15);
    for (int p = 0; p < 15; ++p) numbers[static_cast<size_t>(p)] = 14 - p;
    points.set_mesh_numbers(numbers);
  }
};

TEST(SetParts, EveryRankReceivesItsOverlappingPart) {
  Strip strip;
  for (int ranks : {1, 2, 3}) {
    const std::vector<const runtime::Set*> whole = {&strip.tris, &strip.points};
    const std::vector<std::vector<std::byte>> messages = encode_parts(whole, ranks);
    ASSERT_EQ(messages.size(), static_cast<size_t>(ranks));
    int64_t owned_points = 0, owned_tris = 0;
    for (int r = 0; r < ranks; ++r) {
      SCOPED_TRACE("rank " + std::to_string(r) + " of " + std::to_string(ranks));
      LocalSets part = decode_part(messages[static_cast<size_t>(r)]);
      ASSERT_EQ(part.sets.size(), 2u);
      const runtime::Set& tris = *part.sets[0];
      const runtime::Set& points = *part.sets[1];
      EXPECT_EQ(tris.name(), "tris");
      EXPECT_EQ(points.name(), "points");
      EXPECT_EQ(part.whole_sizes, (std::vector<int32_t>{16, 15}));
      ASSERT_EQ(tris.endpoint_sets().size(), 3u);
      EXPECT_EQ(tris.endpoint_sets()[0], &points);
      const SetPart& pl = part.layouts[1];
      const SetPart& tl = part.layouts[0];
      owned_points += static_cast<int64_t>(pl.owned.size());
      owned_tris += static_cast<int64_t>(tl.owned.size());
      ASSERT_EQ(points.size(), static_cast<int>(pl.global.size()));
      for (int i = 0; i < points.size(); ++i) {
        const int g = pl.global[static_cast<size_t>(i)];
        EXPECT_EQ(points.field("x").at<double>(i)[1], 0.5 * g);
        EXPECT_EQ(*points.field("tag").at<int32_t>(i), 100 + g);
        EXPECT_EQ(points.mesh_number(i), 14 - g);
      }
      ASSERT_EQ(tris.size(), static_cast<int>(tl.global.size()));
      for (int e = 0; e < tris.size(); ++e) {
        const int g = tl.global[static_cast<size_t>(e)];
        EXPECT_EQ(*tris.field("area").at<double>(e), 0.25 * g);
        for (int k = 0; k < 3; ++k)
          EXPECT_EQ(pl.global[static_cast<size_t>(tris.endpoint(e, k))], strip.tris.endpoint(g, k));
      }
      // Each owned point's triangles are all here.
      for (int i : pl.owned) {
        int held = 0, all = 0;
        for (int e = 0; e < tris.size(); ++e)
          for (int k = 0; k < 3; ++k) held += tris.endpoint(e, k) == i;
        for (int e = 0; e < strip.tris.size(); ++e)
          for (int k = 0; k < 3; ++k)
            all += strip.tris.endpoint(e, k) == pl.global[static_cast<size_t>(i)];
        EXPECT_EQ(held, all) << "point " << pl.global[static_cast<size_t>(i)];
      }
    }
    EXPECT_EQ(owned_points, 15);
    EXPECT_EQ(owned_tris, 16);
  }
}

TEST(SetParts, ABrokenMessageIsAnError) {
  Strip strip;
  std::vector<std::byte> m = encode_parts({&strip.points, &strip.tris}, 2)[1];
  m.resize(m.size() - 3);
  EXPECT_THROW(decode_part(m), std::runtime_error);
}

TEST(SetParts, ASetItCannotCutIsNamed) {
  runtime::Set a{"a"}, b{"b"};
  a.add_many(2);
  b.add_many(2);
  runtime::Set mixed{"mixed", {&a, &b}};
  mixed.add({0, 1});
  try {
    encode_parts({&a, &b, &mixed}, 2);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("set 'mixed' has endpoints in more than one set"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace simit::dist
