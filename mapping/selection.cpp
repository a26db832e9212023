#include "mapping/selection.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "meshing/core/error.hpp"

namespace curvefem::mapping {

bool selects(const Selection& s, const SelectionSite& site) {
  const bool on_box = site.box_side >= 0;
  switch (s.kind) {
    case Selection::Kind::outer_box:
      return on_box && (s.box_side < 0 || s.box_side == site.box_side);
    case Selection::Kind::all:
      return !on_box;
    case Selection::Kind::tag:
      return !on_box && site.tag == s.tag;
    case Selection::Kind::box:
      return (site.x.array() >= s.lo.array()).all() && (site.x.array() <= s.hi.array()).all();
    case Selection::Kind::plane:
      return (site.x - s.point).dot(s.direction) >= 0;
    case Selection::Kind::normal: {
      if (on_box) return false;
      const double c = std::cos(s.angle_deg * std::numbers::pi / 180.0);
      return site.normal.dot(s.direction) >= c * s.direction.norm() - 1e-12;
    }
    case Selection::Kind::all_of:
      for (const auto& c : s.children)
        if (!selects(c, site)) return false;
      return true;
    case Selection::Kind::any_of:
      for (const auto& c : s.children)
        if (selects(c, site)) return true;
      return false;
    case Selection::Kind::none_of:
      for (const auto& c : s.children)
        if (selects(c, site)) return false;
      return true;
  }
  return false;
}

bool selects_point(const Selection& s, const SelectionSite& site) {
  if (site.box_side >= 0 && !uses_outer_box(s)) return false;
  return selects(s, site);
}

bool uses_outer_box(const Selection& s) {
  if (s.kind == Selection::Kind::outer_box) return true;
  for (const auto& c : s.children)
    if (uses_outer_box(c)) return true;
  return false;
}

const char* box_side_name(int side) {
  static const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  return side >= 0 && side < 6 ? names[side] : "all";
}

int box_side_of(const Eigen::Vector3d& x, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                double tol) {
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(x[axis] - lo[axis]) <= tol) return 2 * axis;
    if (std::abs(x[axis] - hi[axis]) <= tol) return 2 * axis + 1;
  }
  return -1;
}

Eigen::Vector3d face_normal(const SurfaceMesh& input, int f) {
  const Eigen::Vector3d a = input.V.row(input.F(f, 0)).transpose();
  const Eigen::Vector3d b = input.V.row(input.F(f, 1)).transpose();
  const Eigen::Vector3d c = input.V.row(input.F(f, 2)).transpose();
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

SelectionSite site_of(const SurfaceMesh& input, const InputPoint& p) {
  CF_VERIFY(p.face >= 0 && p.face < input.num_faces(), "selection: input face out of range");
  SelectionSite s;
  s.x = p.position;
  s.tag = input.has_tags() ? input.tags[p.face] : -1;
  s.normal = face_normal(input, p.face);
  return s;
}

bool uses_face_data(const Selection& s) {
  if (s.kind == Selection::Kind::tag || s.kind == Selection::Kind::normal) return true;
  for (const auto& c : s.children)
    if (uses_face_data(c)) return true;
  return false;
}

double face_coverage(const Selection& s, const SurfaceMesh& input, int f) {
  InputPoint p;
  p.face = f;
  int hits = 0;
  for (int j = 0; j < 4; ++j) {
    p.bary = j < 3 ? Eigen::Vector3d(Eigen::Vector3d::Unit(j)) : Eigen::Vector3d::Constant(1.0 / 3);
    p.position.setZero();
    for (int i = 0; i < 3; ++i) p.position += p.bary[i] * input.V.row(input.F(f, i)).transpose();
    hits += selects(s, site_of(input, p));
  }
  return hits / 4.0;
}

}  // namespace curvefem::mapping
