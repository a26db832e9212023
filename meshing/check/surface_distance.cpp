#include "meshing/check/surface_distance.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem::check {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

}  // namespace

Eigen::VectorXd distances_to_surface(const Eigen::MatrixXd& P, const Eigen::MatrixXd& V,
                                     const Eigen::MatrixXi& F) {
  std::vector<Triangle> triangles;
  triangles.reserve(std::size_t(F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    Point c[3];
    for (int k = 0; k < 3; ++k) c[k] = Point(V(F(f, k), 0), V(F(f, k), 1), V(F(f, k), 2));
    const Triangle t(c[0], c[1], c[2]);
    if (!t.is_degenerate()) triangles.push_back(t);
  }
  CF_VERIFY(!triangles.empty(), "distances_to_surface: the surface has no non-degenerate face");
  Tree tree(triangles.cbegin(), triangles.cend());
  tree.accelerate_distance_queries();
  Eigen::VectorXd d(P.rows());
  tbb::parallel_for(Eigen::Index(0), P.rows(), [&](Eigen::Index i) {
    d[i] = std::sqrt(tree.squared_distance(Point(P(i, 0), P(i, 1), P(i, 2))));
  });
  return d;
}

Eigen::MatrixXd surface_samples(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int density) {
  CF_VERIFY(density >= 1, "surface_samples: density must be at least 1");
  const int n = density;
  const Eigen::Index per_face = (n + 1) * (n + 2) / 2;
  Eigen::MatrixXd S(V.rows() + F.rows() * per_face, 3);
  S.topRows(V.rows()) = V;
  Eigen::Index row = V.rows();
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const int k = n - i - j;
        S.row(row++) = (i * V.row(F(f, 0)) + j * V.row(F(f, 1)) + k * V.row(F(f, 2))) / double(n);
      }
  return S;
}

HausdorffEstimate sampled_hausdorff(const Eigen::MatrixXd& Va, const Eigen::MatrixXi& Fa,
                                    const Eigen::MatrixXd& Vb, const Eigen::MatrixXi& Fb,
                                    int density) {
  HausdorffEstimate h;
  const Eigen::VectorXd ab = distances_to_surface(surface_samples(Va, Fa, density), Vb, Fb);
  const Eigen::VectorXd ba = distances_to_surface(surface_samples(Vb, Fb, density), Va, Fa);
  h.a_to_b = ab.size() ? ab.maxCoeff() : 0.0;
  h.b_to_a = ba.size() ? ba.maxCoeff() : 0.0;
  h.mean_a_to_b = ab.size() ? ab.mean() : 0.0;
  h.mean_b_to_a = ba.size() ? ba.mean() : 0.0;
  return h;
}

double winding_number(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                      const Eigen::Vector3d& x) {
  double sum = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = Eigen::Vector3d(V.row(F(f, 0))) - x,
                          b = Eigen::Vector3d(V.row(F(f, 1))) - x,
                          c = Eigen::Vector3d(V.row(F(f, 2))) - x;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    sum += 2 * std::atan2(a.dot(b.cross(c)),
                          la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return sum / (4 * std::numbers::pi);
}

}  // namespace curvefem::check
