// Real meshes (data label): each algorithm reaches its target on two meshes of ../shared/data.

#include <gtest/gtest.h>

#include "meshing/editing/algorithms/surface_edit_mesh.hpp"
#include "meshing/editing/algorithms/surface_remeshing.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace ed = curvefem::meshing::editing;
using curvefem::SurfaceMesh;

namespace {
long euler_characteristic(const SurfaceMesh& s) {
  ed::SurfaceEditMesh m;
  m.load(s);
  return long(m.num_vertices()) - long(m.get_edges().size()) + long(m.num_cells());
}
}  // namespace

class EditingData : public ::testing::TestWithParam<const char*> {};

TEST_P(EditingData, AlgorithmsReachTheirTargets) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << "../shared/data not found: real-mesh editing test skipped";
  const SurfaceMesh input = curvefem::io::read_surface(*dir / "dev" / GetParam());
  const int target = input.num_faces() / 10;
  for (auto algorithm : {ed::RemeshAlgorithm::shortest_collapse, ed::RemeshAlgorithm::qslim}) {
    ed::RemeshOptions o;
    o.algorithm = algorithm;
    o.target_faces = std::size_t(target);
    o.threads = 2;
    const ed::RemeshResult r = ed::remesh(input, o);
    EXPECT_LE(r.mesh.num_faces(), target);
    EXPECT_GE(r.mesh.num_faces(), target - 4);
    EXPECT_EQ(euler_characteristic(r.mesh), euler_characteristic(input));
  }
  const ed::SurfaceQuality in = ed::measure_quality(input, input);
  ed::RemeshOptions o;
  o.algorithm = ed::RemeshAlgorithm::isotropic;
  o.target_edge = 2 * in.mean_edge;
  o.threads = 2;
  const ed::RemeshResult r = ed::remesh(input, o);
  const ed::SurfaceQuality q = ed::measure_quality(r.mesh, input);
  EXPECT_NEAR(q.mean_edge, o.target_edge, 0.2 * o.target_edge);
  EXPECT_EQ(euler_characteristic(r.mesh), euler_characteristic(input));
}

INSTANTIATE_TEST_SUITE_P(Editing, EditingData, ::testing::Values("armadillo.obj", "spot.obj"),
                         [](const auto& info) {
                           const std::string name(info.param);
                           return name.substr(0, name.find('.'));
                         });
