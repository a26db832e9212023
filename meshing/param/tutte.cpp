// Tutte embedding per chart (sparse LU on the interior vertices), area scaling and grid layout.
#include "meshing/param/tutte.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseLU>
#include <cmath>
#include <numbers>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::param {

namespace {

// Unit-circle Tutte embedding of chart c; writes the rows of its UV vertices into `uv`.
void embed_chart(const CutMesh& cut, int c, const std::vector<int>& faces, TutteWeights weights,
                 Eigen::MatrixXd& uv) {
  const std::vector<int>& loop = cut.boundary_loops[c];
  // Boundary by arc length.
  std::vector<double> s(loop.size() + 1, 0.0);
  for (std::size_t i = 0; i < loop.size(); ++i)
    s[i + 1] = s[i] + (cut.V.row(loop[(i + 1) % loop.size()]) - cut.V.row(loop[i])).norm();
  std::vector<int> local(cut.num_uv_vertices(), -2);  // -1 boundary, ≥ 0 interior index
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const double a = 2 * std::numbers::pi * s[i] / s.back();
    uv.row(loop[i]) << std::cos(a), std::sin(a);
    local[loop[i]] = -1;
  }
  int ni = 0;
  for (int f : faces)
    for (int k = 0; k < 3; ++k)
      if (local[cut.F(f, k)] == -2) local[cut.F(f, k)] = ni++;
  if (ni == 0) return;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(ni, 2);
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(ni);
  auto add = [&](int i, int j, double w) {  // row of vertex i gets w (x_i − x_j)
    if (local[i] < 0) return;
    diag[local[i]] += w;
    if (local[j] >= 0)
      trip.emplace_back(local[i], local[j], -w);
    else
      rhs.row(local[i]) += w * uv.row(j);
  };
  for (int f : faces)
    for (int k = 0; k < 3; ++k) {
      const int i = cut.F(f, k), j = cut.F(f, (k + 1) % 3), l = cut.F(f, (k + 2) % 3);
      if (weights == TutteWeights::uniform) {
        // each interior edge is seen from both faces: 0.5 per side gives w = 1
        add(i, j, 0.5);
        add(j, i, 0.5);
        continue;
      }
      const Eigen::Vector3d e1 = cut.V.row(j) - cut.V.row(i), e2 = cut.V.row(l) - cut.V.row(i);
      const double n1 = e1.norm(), n2 = e2.norm();
      const double tan_half = e1.cross(e2).norm() / (n1 * n2 + e1.dot(e2));  // tan(θ_i / 2)
      add(i, j, tan_half / n1);
      add(i, l, tan_half / n2);
    }
  for (int i = 0; i < ni; ++i) trip.emplace_back(i, i, diag[i]);
  Eigen::SparseMatrix<double> A(ni, ni);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.compute(A);
  if (lu.info() != Eigen::Success)
    throw MeshingError("param: Tutte system of " + cut.chart_names[c] + " is singular");
  const Eigen::MatrixXd x = lu.solve(rhs);
  for (int f : faces)
    for (int k = 0; k < 3; ++k)
      if (local[cut.F(f, k)] >= 0) uv.row(cut.F(f, k)) = x.row(local[cut.F(f, k)]);
}

}  // namespace

Eigen::MatrixXd tutte_layout(const CutMesh& cut, TutteWeights weights) {
  const int nc = cut.num_charts;
  Eigen::MatrixXd uv = Eigen::MatrixXd::Zero(cut.num_uv_vertices(), 2);
  std::vector<std::vector<int>> faces(nc);
  for (int f = 0; f < cut.num_faces(); ++f) faces[cut.chart[f]].push_back(f);
  std::vector<double> radius(nc);
  std::vector<std::vector<int>> verts(nc);
  for (int c = 0; c < nc; ++c) {
    embed_chart(cut, c, faces[c], weights, uv);
    double a3 = 0, a2 = 0;
    std::vector<char> mark(cut.num_uv_vertices(), 0);
    for (int f : faces[c]) {
      const Eigen::Vector3d p0 = cut.V.row(cut.F(f, 0)), p1 = cut.V.row(cut.F(f, 1)),
                            p2 = cut.V.row(cut.F(f, 2));
      a3 += 0.5 * (p1 - p0).cross(p2 - p0).norm();
      const Eigen::Vector2d q0 = uv.row(cut.F(f, 0)), q1 = uv.row(cut.F(f, 1)),
                            q2 = uv.row(cut.F(f, 2));
      const Eigen::Vector2d d1 = q1 - q0, d2 = q2 - q0;
      a2 += 0.5 * (d1.x() * d2.y() - d1.y() * d2.x());
      for (int k = 0; k < 3; ++k)
        if (!mark[cut.F(f, k)]) {
          mark[cut.F(f, k)] = 1;
          verts[c].push_back(cut.F(f, k));
        }
    }
    CF_VERIFY(a2 > 0, "Tutte embedding of a chart has non-positive area");
    radius[c] = std::sqrt(a3 / a2);  // the unit circle scaled to the 3D area
    for (int u : verts[c]) uv.row(u) *= radius[c];
  }
  const int cols = int(std::ceil(std::sqrt(double(nc))));
  double cell = 0;
  for (double r : radius) cell = std::max(cell, 2.5 * r);
  for (int c = 0; c < nc; ++c) {
    const Eigen::RowVector2d offset(cell * (c % cols), -cell * (c / cols));
    for (int u : verts[c]) uv.row(u) += offset;
  }
  return uv;
}

}  // namespace curvefem::meshing::param
