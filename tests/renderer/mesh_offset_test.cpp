// A mesh far from the origin loads as it would at the origin (renderer/mesh/mesh.h,
// RelativePositions).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "renderer/mesh/mesh.h"

namespace tessera::renderer {
namespace {

// Coordinates far from the origin (georeferenced data) keep the mesh's shape: read as floats
// of the absolute values (steps of 0.5 at 5e6) a unit square lost it (found by review).
TEST(MeshTest, AMeshFarFromTheOriginFitsAsItWouldAtTheOrigin) {
  auto square = [](double ox, double oy, const char* fmt) {
    std::string t;
    for (auto [x, y] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 0.3}})
      t += fmt::format(fmt::runtime(fmt), x + ox, y + oy);
    return t;
  };
  Mesh near = parseObj(square(0, 0, "v {:.17g} {:.17g} 7\n") + "f 1 2 3 4\n", "near.obj");
  Mesh far = parseObj(square(5e6, -5e6, "v {:.17g} {:.17g} 7\n") + "f 1 2 3 4\n", "far.obj");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                           "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  Mesh ply = parsePly(head + square(5e6, -5e6, "{:.17g} {:.17g} 7\n") + "4 0 1 2 3\n", "far.ply");
  for (Mesh* m : {&near, &far, &ply}) fitToUnitBox(*m);
  ASSERT_EQ(far.positions.size(), near.positions.size());
  for (size_t i = 0; i < near.positions.size(); ++i) {
    EXPECT_NEAR(far.positions[i], near.positions[i], 1e-6) << i;
    EXPECT_NEAR(ply.positions[i], near.positions[i], 1e-6) << i;
  }
  // Vertices further apart than a float holds are refused by name, not as "not finite".
  try {
    parseObj("v 3e38 0 0\nv -3e38 0 0\nv 0 1 0\nf 1 2 3\n", "wide.obj");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("wide.obj: line 2: vertex position lies beyond a float's range (3e38) of the first"),
              std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tessera::renderer
