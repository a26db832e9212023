#include "fem/problems/interpolation.hpp"

#include "fem/assembly/tabulation.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::fem {

Eigen::MatrixXd interpolate_field(const FunctionSpace& from, const Eigen::VectorXd& u, int c,
                                  const FunctionSpace& to) {
  CF_VERIFY(from.cell_dofs.rows() == to.cell_dofs.rows(), "spaces on different meshes");
  CF_VERIFY(u.size() == static_cast<Eigen::Index>(from.num_dofs) * c, "field size mismatch");
  const ReferenceTabulation tab =
      tabulate(CellKind::tetrahedron, from.degree,
               lagrange_reference_nodes(CellKind::tetrahedron, to.degree));
  const int n = static_cast<int>(from.cell_dofs.cols());
  Eigen::MatrixXd out(to.num_dofs, c), U(n, c);
  for (int cell = 0; cell < from.cell_dofs.rows(); ++cell) {
    for (int a = 0; a < n; ++a)
      for (int i = 0; i < c; ++i) U(a, i) = u[from.cell_dofs(cell, a) * c + i];
    const Eigen::MatrixXd v = tab.values * U;
    for (int l = 0; l < v.rows(); ++l) out.row(to.cell_dofs(cell, l)) = v.row(l);
  }
  return out;
}

LagrangeMesh lagrange_mesh_of_space(const LagrangeMesh& mesh, const FunctionSpace& space) {
  LagrangeMesh out;
  out.kind = CellKind::tetrahedron;
  out.order = space.degree;
  out.nodes = space.dof_points;
  out.cells = space.cell_dofs;
  out.cell_tags = mesh.cell_tags;
  return out;
}

}  // namespace curvefem::fem
