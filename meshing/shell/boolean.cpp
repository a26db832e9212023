#include "meshing/shell/boolean.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <map>
#include <memory>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::shell {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using ExactMesh = CGAL::Surface_mesh<EK::Point_3>;
using IK = CGAL::Exact_predicates_inexact_constructions_kernel;

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

// Each face's origin, tracked through the corefinement: a face property "f:origin" (A's faces
// 0 … #A − 1, B's #A …) that split faces pass to their pieces and copies to the result.
using ExactFace = ExactMesh::Face_index;
struct OriginVisitor : PMP::Corefinement::Default_visitor<ExactMesh> {
  std::shared_ptr<int> current = std::make_shared<int>(-1);  // the face being split
  static ExactMesh::Property_map<ExactFace, int> origin(const ExactMesh& m) {
    return m.property_map<ExactFace, int>("f:origin").first;
  }
  void before_subface_creations(ExactFace f, ExactMesh& tm) { *current = origin(tm)[f]; }
  void after_subface_created(ExactFace f, ExactMesh& tm) { origin(tm)[f] = *current; }
  void after_face_copy(ExactFace from, const ExactMesh& source, ExactFace to, ExactMesh& target) {
    origin(target)[to] = origin(source)[from];
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
  {
    auto oa = ea.add_property_map<ExactFace, int>("f:origin", -1).first;
    for (ExactFace f : ea.faces()) oa[f] = int(f.idx());
    auto ob = eb.add_property_map<ExactFace, int>("f:origin", -1).first;
    for (ExactFace f : eb.faces()) ob[f] = a.num_faces() + int(f.idx());
    out.add_property_map<ExactFace, int>("f:origin", -1);
  }
  const OriginVisitor visitor;
  const auto np = PMP::parameters::visitor(visitor);
  bool ok = false;
  switch (op) {
    case BooleanOperation::union_of:
      ok = PMP::corefine_and_compute_union(ea, eb, out, np);
      break;
    case BooleanOperation::intersection:
      ok = PMP::corefine_and_compute_intersection(ea, eb, out, np);
      break;
    case BooleanOperation::difference:
      ok = PMP::corefine_and_compute_difference(ea, eb, out, np);
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
  std::vector<int> origin;
  const auto origin_map = OriginVisitor::origin(out);
  int f = 0;
  for (auto face : out.faces()) {
    origin.push_back(origin_map[face]);
    int k = 0;
    for (auto v : CGAL::vertices_around_face(out.halfedge(face), out)) {
      CF_VERIFY(k < 3, "boolean: a result face is not a triangle");
      r.mesh.F(f, k++) = id.at(v);
    }
    ++f;
  }
  if (r.mesh.num_faces() == 0) throw MeshingError("boolean: the result is empty");
  r.operand.resize(std::size_t(r.mesh.num_faces()));
  r.operand_face.resize(std::size_t(r.mesh.num_faces()));
  auto point = [](const Eigen::MatrixXd& V, int v) {
    return IK::Point_3(V(v, 0), V(v, 1), V(v, 2));
  };
  for (int g = 0; g < r.mesh.num_faces(); ++g) {
    const int o = origin[std::size_t(g)];
    CF_VERIFY(o >= 0 && o < a.num_faces() + b.num_faces(),
              "boolean: a result face has no origin in the operands");
    const bool from_a = o < a.num_faces();
    const SurfaceMesh& operand = from_a ? a : b;
    const int face = from_a ? o : o - a.num_faces();
    r.operand[std::size_t(g)] = from_a ? 0 : 1;
    r.operand_face[std::size_t(g)] = face;
    // How far the rounded result face lies from its origin: its corners' distances.
    const IK::Triangle_3 t(point(operand.V, operand.F(face, 0)),
                           point(operand.V, operand.F(face, 1)),
                           point(operand.V, operand.F(face, 2)));
    for (int k = 0; k < 3; ++k)
      r.max_origin_distance = std::max(
          r.max_origin_distance,
          std::sqrt(CGAL::to_double(CGAL::squared_distance(point(r.mesh.V, r.mesh.F(g, k)), t))));
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
