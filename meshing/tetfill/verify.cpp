// verify_tetfill: an independent check of a filled interior, sharing no code with fill_interior.
// Exact orient3d (CGAL filtered predicates) for every tet; the oriented faces of all tets are
// sorted by vertex set, so faces used once (the boundary chain) can be compared with F as
// oriented triangles, and faces used twice must carry opposite orientations.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <vector>

#include "meshing/tetfill/tetfill.hpp"

namespace curvefem::meshing::tetfill {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

/// A face keyed by its sorted vertex ids; `even` tells whether (a, b, c) as given is an even
/// permutation of the sorted triple (the orientation class of the oriented triangle).
struct OrientedFace {
  std::array<int, 3> key;
  bool even;
  int source;  ///< tet or input face id (for debugging)
};

OrientedFace make_face(int a, int b, int c, int source) {
  OrientedFace f{{a, b, c}, true, source};
  // Sorting three entries with explicit swaps, flipping parity on each swap.
  auto& k = f.key;
  if (k[0] > k[1]) std::swap(k[0], k[1]), f.even = !f.even;
  if (k[1] > k[2]) std::swap(k[1], k[2]), f.even = !f.even;
  if (k[0] > k[1]) std::swap(k[0], k[1]), f.even = !f.even;
  return f;
}

bool key_less(const OrientedFace& x, const OrientedFace& y) { return x.key < y.key; }

double det3(const Eigen::Vector3d& u, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  return u.dot(v.cross(w));
}

}  // namespace

TetFillVerification verify_tetfill(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                   const TetFillResult& result) {
  TetFillVerification out;
  const Eigen::MatrixXd& X = result.V;
  const Eigen::MatrixXi& T = result.T;
  const long long nx = X.rows();
  out.tets = static_cast<int>(T.rows());

  // Boundary vertices: bit-identical copies of the input, in the same rows.
  for (long long i = 0; i < V.rows(); ++i) {
    if (i >= nx || X.cols() != 3 || result.boundary_vertices != V.rows() || X(i, 0) != V(i, 0) ||
        X(i, 1) != V(i, 1) || X(i, 2) != V(i, 2)) {
      ++out.moved_boundary_vertices;
    }
  }

  // Exact orientation of every tet; outward oriented faces of the valid ones.
  std::vector<Point> points;
  points.reserve(nx);
  for (long long i = 0; i < nx && X.cols() == 3; ++i)
    points.emplace_back(X(i, 0), X(i, 1), X(i, 2));
  std::vector<OrientedFace> faces;
  faces.reserve(4 * T.rows());
  if (T.cols() != 4) out.non_positive_tets = out.tets;
  for (long long t = 0; t < T.rows() && T.cols() == 4; ++t) {
    const int a = T(t, 0), b = T(t, 1), c = T(t, 2), d = T(t, 3);
    const bool in_range = std::min({a, b, c, d}) >= 0 &&
                          std::max({a, b, c, d}) < static_cast<long long>(points.size());
    if (!in_range ||
        CGAL::orientation(points[a], points[b], points[c], points[d]) != CGAL::POSITIVE) {
      ++out.non_positive_tets;
      continue;
    }
    // det(b-a, c-a, d-a) > 0: the outward faces are (a,c,b), (a,b,d), (a,d,c), (b,c,d).
    const int s = static_cast<int>(t);
    faces.push_back(make_face(a, c, b, s));
    faces.push_back(make_face(a, b, d, s));
    faces.push_back(make_face(a, d, c, s));
    faces.push_back(make_face(b, c, d, s));
  }
  std::sort(faces.begin(), faces.end(), key_less);

  // Boundary chain: faces used once. Interior faces: exactly two uses, opposite orientations.
  std::vector<OrientedFace> boundary;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) {
      boundary.push_back(faces[i]);
    } else if (j - i > 2 || faces[i].even == faces[i + 1].even) {
      ++out.bad_interior_faces;
    }
    i = j;
  }

  // Compare with F as oriented triangles (both lists sorted by key).
  std::vector<OrientedFace> input;
  input.reserve(F.rows());
  for (long long f = 0; f < F.rows(); ++f) {
    input.push_back(make_face(F(f, 0), F(f, 1), F(f, 2), static_cast<int>(f)));
  }
  std::sort(input.begin(), input.end(), key_less);
  size_t i = 0, j = 0;
  while (i < input.size() || j < boundary.size()) {
    if (j == boundary.size() || (i < input.size() && input[i].key < boundary[j].key)) {
      ++out.missing_boundary_faces, ++i;
    } else if (i == input.size() || boundary[j].key < input[i].key) {
      ++out.extra_boundary_faces, ++j;
    } else {
      if (input[i].even != boundary[j].even)
        ++out.missing_boundary_faces, ++out.extra_boundary_faces;
      ++i, ++j;
    }
  }

  // Volumes, as cones from a common reference point to limit cancellation.
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  if (V.rows() > 0) c = V.colwise().mean().transpose();
  double enclosed = 0;
  for (long long f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), d = F(f, 2);
    if (std::min({a, b, d}) < 0 || std::max({a, b, d}) >= V.rows()) continue;
    enclosed += det3(V.row(a).transpose() - c, V.row(b).transpose() - c, V.row(d).transpose() - c);
  }
  double filled = 0;
  for (long long t = 0; t < T.rows() && T.cols() == 4 && X.cols() == 3; ++t) {
    const int a = T(t, 0), b = T(t, 1), e = T(t, 2), d = T(t, 3);
    if (std::min({a, b, e, d}) < 0 || std::max({a, b, e, d}) >= nx) continue;
    const Eigen::Vector3d x0 = X.row(a).transpose();
    filled += det3(X.row(b).transpose() - x0, X.row(e).transpose() - x0, X.row(d).transpose() - x0);
  }
  out.enclosed_volume = enclosed / 6.0;
  out.tet_volume = filled / 6.0;
  out.volume_error_rel = out.enclosed_volume != 0 ? std::abs(out.tet_volume - out.enclosed_volume) /
                                                        std::abs(out.enclosed_volume)
                                                  : (out.tet_volume == 0 ? 0.0 : 1.0);
  return out;
}

}  // namespace curvefem::meshing::tetfill
