// MSH 4.1 output checked through the Gmsh API (nodes, Gmsh's own interpolation, physical groups);
// read_msh round trips, MSH 2.2 input and rejection of bad files.
#include <gmsh.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <random>

#include "meshing/core/error.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/io/msh_io.hpp"
#include "tests/meshing/io/volume_test_meshes.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {

const char* family(CellKind kind) {
  return kind == CellKind::triangle ? "Triangle" : "Tetrahedron";
}

void spit(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Comparison independent of node and cell numbering (Gmsh's MSH 2.2 writer renumbers
/// elements entity by entity): every cell of `b` matches one cell of `a` node by node, with the
/// same tag. Gmsh writes coordinates with 16 significant digits, not always enough for an exact
/// round trip: 3e-15.
void expect_same_cells(const LagrangeMesh& a, const LagrangeMesh& b) {
  ASSERT_EQ(a.kind, b.kind);
  ASSERT_EQ(a.order, b.order);
  ASSERT_EQ(a.num_cells(), b.num_cells());
  ASSERT_EQ(a.cells.cols(), b.cells.cols());
  ASSERT_EQ(a.cell_tags.size(), b.cell_tags.size());
  std::vector<bool> used(a.num_cells(), false);
  for (int cb = 0; cb < b.num_cells(); ++cb) {
    int match = -1;
    for (int ca = 0; ca < a.num_cells() && match < 0; ++ca) {
      bool same = !used[ca];
      for (int i = 0; same && i < a.cells.cols(); ++i)
        same = (a.nodes.row(a.cells(ca, i)) - b.nodes.row(b.cells(cb, i))).norm() < 3e-15;
      if (same) match = ca;
    }
    ASSERT_GE(match, 0) << "cell " << cb << " matches no original cell";
    used[match] = true;
    if (a.cell_tags.size() > 0) {
      EXPECT_EQ(a.cell_tags[match], b.cell_tags[cb]) << "cell " << cb;
    }
  }
}

}  // namespace

// Runs first in this binary, so it is the first (table-building) call: asking for a permutation
// while holding a session with a live model (as cad_part.cpp does) must not clear that model.
TEST(MshIo, PermutationQueryKeepsTheCurrentGmshModel) {
  io::GmshSession session("keep_me");
  const int volume = gmsh::model::addDiscreteEntity(3);
  gmsh::model::mesh::addNodes(3, volume, {1, 2, 3}, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  const auto perm = io::gmsh_node_permutation(CellKind::tetrahedron, 4);
  EXPECT_EQ(perm.size(), 35u);
  std::vector<std::size_t> tags;
  std::vector<double> coords, parametric;
  gmsh::model::mesh::getNodes(tags, coords, parametric);
  EXPECT_EQ(tags.size(), 3u);
  std::string name;
  gmsh::model::getCurrent(name);
  EXPECT_EQ(name, "keep_me");
}

// Test 3: what Gmsh reads from our file is our mesh, node by node, and Gmsh's own basis and
// Jacobian evaluation reproduce LagrangeMesh::map. Physical groups carry the cell tags.
TEST(MshIo, GmshReadsOurHighOrderMeshes) {
  const auto dir = test::scratch_dir("msh_gmsh_api");
  for (CellKind kind : {CellKind::tetrahedron, CellKind::triangle})
    for (int k = 1; k <= 4; ++k) {
      SCOPED_TRACE(std::string(family(kind)) + " order " + std::to_string(k));
      const LagrangeMesh mesh = test::curved_patch(kind, k);
      const auto path = dir / (std::string(family(kind)) + std::to_string(k) + ".msh");
      const auto perm = io::gmsh_node_permutation(kind, k);  // before the session (cached)
      io::write_msh(path, mesh);

      io::GmshSession session("msh_io_test");
      gmsh::open(path.string());
      const int dim = cell_dimension(kind);
      const int type = gmsh::model::mesh::getElementType(family(kind), k);
      std::vector<std::size_t> element_tags, node_tags;
      gmsh::model::mesh::getElementsByType(type, element_tags, node_tags);
      ASSERT_EQ(static_cast<int>(element_tags.size()), mesh.num_cells());
      const int n = mesh.nodes_per_cell();
      ASSERT_EQ(node_tags.size(), element_tags.size() * n);

      std::vector<std::size_t> all_nodes;
      std::vector<double> coords, parametric;
      gmsh::model::mesh::getNodes(all_nodes, coords, parametric);
      EXPECT_EQ(static_cast<int>(all_nodes.size()), mesh.num_nodes());  // all nodes written
      std::map<std::size_t, Eigen::RowVector3d> position;
      for (std::size_t i = 0; i < all_nodes.size(); ++i)
        position[all_nodes[i]] =
            Eigen::RowVector3d(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);

      // Nodes per element, through the permutation: bit-identical.
      std::vector<int> cell_of(element_tags.size());
      for (std::size_t e = 0; e < element_tags.size(); ++e) {
        const int c = static_cast<int>(element_tags[e]) - 1;
        ASSERT_TRUE(c >= 0 && c < mesh.num_cells());
        cell_of[e] = c;
        for (int i = 0; i < n; ++i)
          EXPECT_EQ(position.at(node_tags[e * n + i]), mesh.nodes.row(mesh.cells(c, perm[i])));
      }

      // Gmsh's interpolation at 20 random reference points, two ways.
      std::mt19937 rng(11);
      std::vector<Eigen::Vector3d> xis;
      std::vector<double> local;
      for (int s = 0; s < 20; ++s) {
        xis.push_back(test::random_reference_point(rng, kind));
        local.insert(local.end(), {xis.back()[0], xis.back()[1], xis.back()[2]});
      }
      std::vector<double> jacobians, determinants, points;
      gmsh::model::mesh::getJacobians(type, local, jacobians, determinants, points);
      ASSERT_EQ(points.size(), element_tags.size() * 20 * 3);
      int components = 0, orientations = 0;
      std::vector<double> basis;
      gmsh::model::mesh::getBasisFunctions(type, local, "Lagrange", components, basis,
                                           orientations);
      ASSERT_EQ(basis.size(), static_cast<std::size_t>(20 * n));
      double worst_jacobian = 0.0, worst_basis = 0.0, worst_derivative = 0.0;
      const double size = test::mesh_size(mesh);
      for (std::size_t e = 0; e < element_tags.size(); ++e)
        for (int s = 0; s < 20; ++s) {
          const Eigen::Vector3d ours = mesh.map(cell_of[e], xis[s]);
          const std::size_t at = (e * 20 + s) * 3;
          worst_jacobian =
              std::max(worst_jacobian,
                       (Eigen::Vector3d(points[at], points[at + 1], points[at + 2]) - ours).norm());
          Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
          for (int i = 0; i < n; ++i) x += basis[s * n + i] * position.at(node_tags[e * n + i]);
          worst_basis = std::max(worst_basis, (x.transpose() - ours).norm());
          // dx/du, dx/dv (, dx/dw) columns against our Jacobian.
          const Eigen::MatrixXd J = mesh.jacobian(cell_of[e], xis[s]);
          for (int d = 0; d < dim; ++d)
            for (int r = 0; r < 3; ++r)
              worst_derivative = std::max(
                  worst_derivative, std::abs(jacobians[(e * 20 + s) * 9 + 3 * d + r] - J(r, d)));
        }
      std::printf(
          "[msh] %s order %d: |gmsh - map| / size = %.2e (getJacobians), %.2e (basis); "
          "|dx/du diff| = %.2e\n",
          family(kind), k, worst_jacobian / size, worst_basis / size, worst_derivative);
      EXPECT_LT(worst_jacobian / size, 1e-12);
      EXPECT_LT(worst_basis / size, 1e-12);
      EXPECT_LT(worst_derivative, 1e-10);

      // Physical groups: one per distinct tag, holding exactly the cells with that tag.
      gmsh::vectorpair groups;
      gmsh::model::getPhysicalGroups(groups, dim);
      ASSERT_EQ(groups.size(), 2u);
      std::map<int, int> tag_of_cell;
      for (const auto& [gdim, tag] : groups) {
        std::vector<int> entities;
        gmsh::model::getEntitiesForPhysicalGroup(gdim, tag, entities);
        for (int entity : entities) {
          std::vector<std::size_t> tags_in_entity, nodes_in_entity;
          gmsh::model::mesh::getElementsByType(type, tags_in_entity, nodes_in_entity, entity);
          for (std::size_t t : tags_in_entity) tag_of_cell[static_cast<int>(t) - 1] = tag;
        }
      }
      ASSERT_EQ(static_cast<int>(tag_of_cell.size()), mesh.num_cells());
      for (int c = 0; c < mesh.num_cells(); ++c) EXPECT_EQ(tag_of_cell[c], mesh.cell_tags[c]);
    }
}

// Test 4 (MSH part): read_msh gives back exactly what write_msh wrote.
TEST(MshIo, ReadMshRoundTrip) {
  const auto dir = test::scratch_dir("msh_round_trip");
  for (CellKind kind : {CellKind::tetrahedron, CellKind::triangle})
    for (int k = 1; k <= 4; ++k)
      for (bool tagged : {true, false}) {
        SCOPED_TRACE(std::string(family(kind)) + " order " + std::to_string(k) +
                     (tagged ? " tagged" : " untagged"));
        const LagrangeMesh mesh = test::curved_patch(kind, k, tagged);
        const auto path = dir / "m.msh";
        io::write_msh(path, mesh);
        const LagrangeMesh back = io::read_msh(path);
        EXPECT_EQ(back.kind, kind);
        EXPECT_EQ(back.order, k);
        EXPECT_EQ(back.nodes, mesh.nodes);
        EXPECT_EQ(back.cells, mesh.cells);
        EXPECT_EQ(back.cell_tags, mesh.cell_tags);
      }
}

// Tag 0 = no physical group; it survives the round trip next to tagged cells.
TEST(MshIo, ZeroTagMeansNoPhysicalGroup) {
  const auto dir = test::scratch_dir("msh_zero_tag");
  LagrangeMesh mesh = test::curved_patch(CellKind::tetrahedron, 2);
  mesh.cell_tags[0] = 0;
  mesh.cell_tags[5] = 0;
  io::write_msh(dir / "m.msh", mesh);
  const LagrangeMesh back = io::read_msh(dir / "m.msh");
  EXPECT_EQ(back.cell_tags, mesh.cell_tags);
  EXPECT_EQ(back.cells, mesh.cells);
  mesh.cell_tags[1] = -4;
  EXPECT_THROW(io::write_msh(dir / "n.msh", mesh), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "n.msh"));
}

// Files written by Gmsh itself in MSH 2.2 (and 4.1), with boundary triangles next to the
// tetrahedra: read_msh takes the tetrahedra.
TEST(MshIo, ReadsGmshWrittenMsh22And41) {
  const auto dir = test::scratch_dir("msh_from_gmsh");
  for (int k = 1; k <= 4; ++k) {
    SCOPED_TRACE("order " + std::to_string(k));
    const LagrangeMesh mesh = test::curved_patch(CellKind::tetrahedron, k);
    io::write_msh(dir / "ours.msh", mesh);
    const LagrangeMesh surface = test::curved_patch(CellKind::triangle, k);
    {
      io::GmshSession session("msh_io_convert");
      gmsh::open((dir / "ours.msh").string());
      // Add a few triangles of the same order on a separate surface entity: lower dimension,
      // must be ignored by read_msh.
      const int surf = gmsh::model::addDiscreteEntity(2);
      std::vector<std::size_t> tags, coords_tags;
      std::vector<double> coords;
      for (int i = 0; i < surface.num_nodes(); ++i) {
        coords_tags.push_back(100000 + i);
        for (int d = 0; d < 3; ++d) coords.push_back(surface.nodes(i, d) + 5.0);
      }
      gmsh::model::mesh::addNodes(2, surf, coords_tags, coords);
      const auto perm = io::gmsh_node_permutation(CellKind::triangle, k);
      std::vector<std::size_t> element_nodes;
      for (int c = 0; c < surface.num_cells(); ++c)
        for (int i = 0; i < surface.nodes_per_cell(); ++i)
          element_nodes.push_back(100000 + surface.cells(c, perm[i]));
      gmsh::model::mesh::addElementsByType(surf, gmsh::model::mesh::getElementType("Triangle", k),
                                           {}, element_nodes);
      gmsh::model::addPhysicalGroup(2, {surf}, 99);
      gmsh::option::setNumber("Mesh.MshFileVersion", 2.2);
      gmsh::write((dir / "gmsh22.msh").string());
      gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
      gmsh::write((dir / "gmsh41.msh").string());
    }
    for (const char* name : {"gmsh22.msh", "gmsh41.msh"}) {
      SCOPED_TRACE(name);
      const LagrangeMesh back = io::read_msh(dir / name);
      expect_same_cells(mesh, back);
    }
  }
}

TEST(MshIo, RejectsBadFiles) {
  const auto dir = test::scratch_dir("msh_bad");
  try {
    io::read_msh(dir / "missing.msh");
    ADD_FAILURE() << "missing file accepted";
  } catch (const IoError& e) {  // cannot open: I/O failure (exit 4), as every reader
    EXPECT_EQ(e.context().file, (dir / "missing.msh").string());
  }
  spit(dir / "garbage.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1\nxx");
  EXPECT_THROW(io::read_msh(dir / "garbage.msh"), InputError);
  // Valid MSH with only lines: no triangles or tetrahedra.
  spit(dir / "lines.msh",
       "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n$EndNodes\n"
       "$Elements\n1\n1 1 2 0 1 1 2\n$EndElements\n");
  EXPECT_THROW(io::read_msh(dir / "lines.msh"), InputError);
  // Truncated copy of a good file.
  const LagrangeMesh mesh = test::curved_patch(CellKind::tetrahedron, 3);
  io::write_msh(dir / "good.msh", mesh);
  std::ifstream in(dir / "good.msh", std::ios::binary);
  const std::string good{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  spit(dir / "truncated.msh", good.substr(0, good.size() * 2 / 3));
  EXPECT_THROW(io::read_msh(dir / "truncated.msh"), InputError);
}

// Deterministic byte-level fuzzing of read_msh on our own output: read or InputError, nothing else.
TEST(MshIo, SurvivesByteFlipFuzzing) {
  const auto dir = test::scratch_dir("msh_fuzz");
  const LagrangeMesh mesh = test::curved_patch(CellKind::tetrahedron, 3);
  io::write_msh(dir / "good.msh", mesh);
  std::ifstream in(dir / "good.msh", std::ios::binary);
  const std::string good{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::mt19937 rng(4243);
  int read = 0, rejected = 0;
  for (int t = 0; t < 300; ++t) {
    std::string bytes = good;
    switch (t % 3) {
      case 0:
        for (int j = 0; j < 1 + t % 4; ++j) bytes[rng() % bytes.size()] ^= 1 << (rng() % 8);
        break;
      case 1:
        bytes.resize(rng() % bytes.size());
        break;
      default:
        bytes.insert(rng() % bytes.size(), std::string(1 + rng() % 20, static_cast<char>(rng())));
    }
    spit(dir / "mutated.msh", bytes);
    try {
      io::read_msh(dir / "mutated.msh");
      ++read;
    } catch (const InputError&) {
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "mutation " << t << ": " << e.what();
    }
  }
  std::printf("[msh] fuzzing: %d mutated files read, %d rejected with InputError\n", read,
              rejected);
  EXPECT_EQ(read + rejected, 300);
}
