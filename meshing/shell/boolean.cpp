#include "meshing/shell/boolean.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <map>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::shell {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using ExactMesh = CGAL::Surface_mesh<EK::Point_3>;
using IK = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<IK::Point_3>;
// AABB trees over a CGAL::Surface_mesh's faces: a template instantiation no other module uses.
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<IK, Primitive>>;

template <class M>
M to_cgal(const SurfaceMesh& s) {
  M m;
  std::vector<typename M::Vertex_index> v;
  for (int i = 0; i < s.num_vertices(); ++i)
    v.push_back(m.add_vertex(typename M::Point(s.V(i, 0), s.V(i, 1), s.V(i, 2))));
  for (int f = 0; f < s.num_faces(); ++f)
    if (m.add_face(v[s.F(f, 0)], v[s.F(f, 1)], v[s.F(f, 2)]) == M::null_face())
      throw InputError("boolean: face " + std::to_string(f) +
                       " cannot be added to a manifold mesh (the operand is not an oriented "
                       "manifold)");
  return m;
}

struct Operand {
  Mesh mesh;
  std::unique_ptr<Tree> tree;
  explicit Operand(const SurfaceMesh& s) : mesh(to_cgal<Mesh>(s)) {
    tree = std::make_unique<Tree>(faces(mesh).first, faces(mesh).second, mesh);
    tree->accelerate_distance_queries();
  }
  /// Closest face to p and its squared distance.
  std::pair<int, double> closest(const IK::Point_3& p) const {
    const auto [q, f] = tree->closest_point_and_primitive(p);
    return {int(f.idx()), CGAL::to_double(CGAL::squared_distance(p, q))};
  }
};

Eigen::Vector3d bary_of(const SurfaceMesh& s, int f, const Eigen::Vector3d& x) {
  const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  Eigen::Vector3d w;
  w[1] = n.dot((x - a).cross(c - a)) / area2;
  w[2] = n.dot((b - a).cross(x - a)) / area2;
  w[0] = 1 - w[1] - w[2];
  return w;
}

}  // namespace

BooleanOperation parse_boolean_operation(const std::string& name) {
  if (name == "union") return BooleanOperation::union_of;
  if (name == "intersection") return BooleanOperation::intersection;
  if (name == "difference") return BooleanOperation::difference;
  throw InputError("unknown boolean operation \"" + name +
                   "\" (union, intersection or difference)");
}

BooleanResult corefine_boolean(const SurfaceMesh& a, const SurfaceMesh& b, BooleanOperation op) {
  ExactMesh ea = to_cgal<ExactMesh>(a), eb = to_cgal<ExactMesh>(b), out;
  bool ok = false;
  switch (op) {
    case BooleanOperation::union_of:
      ok = PMP::corefine_and_compute_union(ea, eb, out);
      break;
    case BooleanOperation::intersection:
      ok = PMP::corefine_and_compute_intersection(ea, eb, out);
      break;
    case BooleanOperation::difference:
      ok = PMP::corefine_and_compute_difference(ea, eb, out);
      break;
  }
  if (!ok)
    throw MeshingError(
        "boolean: CGAL's corefinement could not compute the result (are both "
        "operands closed and free of self-intersections?)");
  BooleanResult r;
  std::map<ExactMesh::Vertex_index, int> id;
  r.mesh.V.resize(Eigen::Index(out.number_of_vertices()), 3);
  for (auto v : out.vertices()) {
    const int i = int(id.size());
    id[v] = i;
    const auto& p = out.point(v);
    r.mesh.V.row(i) << CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z());
  }
  r.mesh.F.resize(Eigen::Index(out.number_of_faces()), 3);
  int f = 0;
  for (auto face : out.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(out.halfedge(face), out)) {
      CF_VERIFY(k < 3, "boolean: a result face is not a triangle");
      r.mesh.F(f, k++) = id.at(v);
    }
    ++f;
  }
  if (r.mesh.num_faces() == 0) throw MeshingError("boolean: the result is empty");
  const Operand oa(a), ob(b);
  r.operand.resize(std::size_t(r.mesh.num_faces()));
  r.operand_face.resize(std::size_t(r.mesh.num_faces()));
  for (int g = 0; g < r.mesh.num_faces(); ++g) {
    const Eigen::Vector3d c =
        (r.mesh.V.row(r.mesh.F(g, 0)) + r.mesh.V.row(r.mesh.F(g, 1)) + r.mesh.V.row(r.mesh.F(g, 2)))
            .transpose() /
        3;
    const IK::Point_3 p(c.x(), c.y(), c.z());
    const auto [fa, da] = oa.closest(p);
    const auto [fb, db] = ob.closest(p);
    const bool from_a = da <= db;
    r.operand[std::size_t(g)] = from_a ? 0 : 1;
    r.operand_face[std::size_t(g)] = from_a ? fa : fb;
    r.max_origin_distance = std::max(r.max_origin_distance, std::sqrt(from_a ? da : db));
  }
  return r;
}

std::vector<OperandPoint> locate_in_operands(const SurfaceMesh& a, const SurfaceMesh& b,
                                             const BooleanResult& result,
                                             const Eigen::MatrixXd& points,
                                             const std::vector<int>& faces) {
  std::vector<OperandPoint> out(std::size_t(points.rows()));
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const int g = faces[std::size_t(i)];
    OperandPoint& o = out[std::size_t(i)];
    o.operand = result.operand[std::size_t(g)];
    o.face = result.operand_face[std::size_t(g)];
    o.bary = bary_of(o.operand == 0 ? a : b, o.face, points.row(i).transpose());
  }
  return out;
}

}  // namespace curvefem::meshing::shell
