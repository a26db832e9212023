#include "meshing/editing/algorithms/surface_distance.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>
#include <vector>

namespace curvefem::meshing::editing {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }
}  // namespace

struct SurfaceDistance::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
};

SurfaceDistance::SurfaceDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->triangles.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    m_impl->triangles.emplace_back(to_point(V.row(F(f, 0))), to_point(V.row(F(f, 1))),
                                   to_point(V.row(F(f, 2))));
  }
  m_impl->tree.insert(m_impl->triangles.cbegin(), m_impl->triangles.cend());
  m_impl->tree.build();
  m_impl->tree.accelerate_distance_queries();
}

SurfaceDistance::~SurfaceDistance() = default;

double SurfaceDistance::squared_distance(const Eigen::Vector3d& p) const {
  return CGAL::to_double(m_impl->tree.squared_distance(to_point(p)));
}

Eigen::Vector3d SurfaceDistance::closest_point(const Eigen::Vector3d& p) const {
  const Point q = m_impl->tree.closest_point(to_point(p));
  return {q.x(), q.y(), q.z()};
}

bool SurfaceDistance::triangle_within(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c, double eps) const {
  const double longest =
      std::sqrt(std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}));
  // n subdivisions: covering radius r = longest / (n sqrt 3) <= eps / 2.
  const int n = std::max(1, int(std::ceil(2.0 * longest / (std::sqrt(3.0) * eps))));
  const double r = longest / (double(n) * std::sqrt(3.0));
  const double limit = eps - r;
  if (limit <= 0) return false;
  const double limit2 = limit * limit;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      const Eigen::Vector3d p = (1 - u - v) * a + u * b + v * c;
      if (squared_distance(p) > limit2) return false;
    }
  return true;
}

double SurfaceDistance::max_distance_sampled(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                             const Eigen::Vector3d& c, int n) const {
  double worst = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      worst = std::max(worst, squared_distance((1 - u - v) * a + u * b + v * c));
    }
  return std::sqrt(worst);
}

}  // namespace curvefem::meshing::editing
