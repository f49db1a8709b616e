// Folded quadratic tetrahedra straightened (curved_mesh_repair.hpp, issue 28 item 1).
#include "flexbody/format/tet10_element.hpp"
#include "flexbody/preprocess/curved_mesh_repair.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace fp = flexbody::preprocess;

namespace {

// Two straight-sided tetrahedra sharing the face (1, 2, 3): corners 0-4, then the mid-edge nodes at their edges'
// middles (element 0's six, then element 1's three new edges).
fp::Tet10Mesh two_elements() {
  fp::Tet10Mesh mesh;
  Eigen::Matrix<double, 5, 3> corners;
  corners << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  const int first[4] = {0, 1, 2, 3}, second[4] = {4, 2, 1, 3};  // both positively oriented
  mesh.nodes.resize(5 + 9, 3);
  mesh.nodes.topRows(5) = corners;
  mesh.tets.resize(2, 10);
  int next = 5;
  std::map<std::pair<int, int>, int> middle;
  for (int e = 0; e < 2; ++e) {
    const int* c = e == 0 ? first : second;
    for (int a = 0; a < 4; ++a) mesh.tets(e, a) = c[a];
    for (int k = 0; k < 6; ++k) {
      const auto [i, j] = flexbody::format::kTet10Edges[static_cast<std::size_t>(k)];
      const auto key = std::minmax(c[i], c[j]);
      auto [it, added] = middle.emplace(key, next);
      if (added) mesh.nodes.row(next++) = 0.5 * (corners.row(c[i]) + corners.row(c[j]));
      mesh.tets(e, 4 + k) = it->second;
    }
  }
  EXPECT_EQ(next, 14);
  return mesh;
}

}  // namespace

// Straight elements are not folded; one whose mid-edge node (edge (0,1)) is pushed past corner 2's side is, and
// straightening puts that node back on its chord, moving it by exactly the push, and cures it in one round. The
// neighbour, which does not share that edge, is untouched.
TEST(CurvedMeshRepair, AFoldedElementIsStraightenedAndItsMoveReported) {
  fp::Tet10Mesh mesh = two_elements();
  EXPECT_TRUE(fp::folded_elements(mesh).empty());
  const fp::Tet10Mesh straight = mesh;
  const Eigen::Index pushed = mesh.tets(0, 4);
  mesh.nodes.row(pushed) += Eigen::RowVector3d(0.0, 0.9, 0.0);  // from (0.5, 0, 0) to (0.5, 0.9, 0): past corner 2's reach
  ASSERT_EQ(fp::folded_elements(mesh), std::vector<Eigen::Index>{0});
  const fp::Straightening done = fp::straighten_folded_elements(mesh);
  EXPECT_EQ(done.rounds, 1);
  EXPECT_EQ(done.elements, 1);
  EXPECT_EQ(done.nodes, 1);
  EXPECT_DOUBLE_EQ(done.largest_move_m, 0.9);
  EXPECT_TRUE(fp::folded_elements(mesh).empty());
  EXPECT_EQ(mesh.nodes, straight.nodes);  // back on the chord: the middle is exact in binary
}

// A curved node on the shared edge (1,2), pushed far enough to fold both elements: one round straightens both, and
// the node counts once per element that moved it (the second finds it already on its chord, which is no move).
TEST(CurvedMeshRepair, ASharedEdgeIsStraightenedOnce) {
  fp::Tet10Mesh mesh = two_elements();
  const Eigen::Index shared = mesh.tets(0, 5);  // edge (1, 2) of element 0
  mesh.nodes.row(shared) += Eigen::RowVector3d(2.0, -2.0, 0.0);  // along the edge, past corner 1
  ASSERT_EQ(fp::folded_elements(mesh).size(), 2U);
  const fp::Straightening done = fp::straighten_folded_elements(mesh);
  EXPECT_EQ(done.elements, 2);
  EXPECT_EQ(done.nodes, 1);
  EXPECT_TRUE(fp::folded_elements(mesh).empty());
}

// Straightening cannot cure an element whose corners are inverted: refused, naming the element.
TEST(CurvedMeshRepair, InvertedCornersAreRefused) {
  fp::Tet10Mesh mesh = two_elements();
  std::swap(mesh.tets(1, 1), mesh.tets(1, 2));  // element 1's corners in the other orientation
  try {
    (void)fp::straighten_folded_elements(mesh);
    FAIL() << "an inverted element was straightened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("quadratic element 1 cannot be straightened"), std::string::npos) << e.what();
  }
}
