#include "meshing/shell/verify.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <optional>
#include <set>

#include "meshing/core/error.hpp"
#include "meshing/shell/local_sheets.hpp"
#include "meshing/shell/prism_positivity.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

namespace {

struct SectionScan {
  std::vector<int> failing;  // prisms failing the section condition, increasing
  // Per prism: the smallest cosine between a non-singular half-pillar and the normal of an input
  // face in section contact (1 when no face is in contact, -1 when the prism fails).
  std::vector<double> min_cos;
};

SectionScan scan_section(const Shell& shell, const InputSurfaceIndex& index) {
  // Section condition (the argument is in shell_intersection.cpp): every input face in section
  // contact with a non-degenerate split tet (it meets the open tet, or lies in a facet plane and
  // meets the facet's relative interior) must make a positive dot product, exact sign, with
  // every non-singular half-pillar. Contact with the prism's boundary alone is not checked here:
  // the fibers there belong to the neighbour as well, whose tets see that face.
  // The distortion (thesis §4.4): the smallest half-pillar/normal cosine over the faces in
  // section contact. Candidates go in increasing cosine; the first in contact gives the minimum,
  // so faces passing the pillar test beyond it need no contact test.
  // A locally injective shell: each prism against its local sheet (local_sheets.hpp), reached
  // from the input face it names (face_parent) within the prism's box.
  const std::optional<LocalSheets> sheets =
      shell.local_sheets ? std::optional<LocalSheets>(std::in_place, index) : std::nullopt;
  const int nf = int(shell.F.rows());
  auto row = [](const Eigen::MatrixXd& M, int v) { return Eigen::Vector3d(M.row(v)); };
  SectionScan out;
  out.min_cos.assign(std::size_t(nf), 1.0);
  tbb::parallel_for(0, nf, [&](int f) {
    const Eigen::Vector3i F = shell.F.row(f);
    const int rot = min_rotation(F);
    const bool type_a = is_type_a(F);
    Eigen::AlignedBox3d box;
    std::vector<std::array<Eigen::Vector3d, 4>> tets;
    for (int half = 0; half < 2; ++half)
      for (const auto& tet : split_tets(type_a)) {
        std::array<Eigen::Vector3d, 4> c;
        for (int k = 0; k < 4; ++k) {
          const int v = F[(rot + tet[k] % 3) % 3];
          const Eigen::MatrixXd& M = tet[k] < 3 ? (half == 0 ? shell.base : shell.mid)
                                                : (half == 0 ? shell.mid : shell.top);
          c[k] = row(M, v);
          box.extend(c[k]);
        }
        if ((c[1] - c[0]).cross(c[2] - c[0]).dot(c[3] - c[0]) == 0) continue;  // pinched
        tets.push_back(c);
      }
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> half_pillars;
    for (int k = 0; k < 3; ++k) {
      const int v = F[k];
      if (shell.singular[v]) continue;
      half_pillars.emplace_back(row(shell.base, v), row(shell.mid, v));
      half_pillars.emplace_back(row(shell.mid, v), row(shell.top, v));
    }
    auto in_contact = [&](int t) {
      for (const auto& tet : tets)
        if (index.face_section_contact(t, tet)) return true;
      return false;
    };
    const std::vector<int> candidates =
        sheets ? sheets->sheet({shell.face_parent[std::size_t(f)]}, box)
               : index.faces_in_box(box.min(), box.max());
    std::vector<std::pair<double, int>> transversal;  // (smallest cosine, face)
    bool ok = true;
    for (int t : candidates) {
      bool positive = true;
      for (const auto& [from, to] : half_pillars)
        if (index.face_normal_dot_sign(t, from, to) <= 0) {
          positive = false;
          break;
        }
      if (!positive) {
        if (in_contact(t)) {
          ok = false;
          break;
        }
        continue;
      }
      const auto tri = index.face_triangle(t);
      const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
      double c = 1;
      for (const auto& [from, to] : half_pillars) c = std::min(c, n.dot((to - from).normalized()));
      transversal.emplace_back(c, t);
    }
    if (!ok) {
      out.min_cos[std::size_t(f)] = -1;  // some face in contact is not crossed transversally
      return;
    }
    std::sort(transversal.begin(), transversal.end());
    for (const auto& [c, t] : transversal)
      if (in_contact(t)) {
        out.min_cos[std::size_t(f)] = c;
        break;
      }
  });
  for (int f = 0; f < nf; ++f)
    if (out.min_cos[std::size_t(f)] < 0) out.failing.push_back(f);
  return out;
}

}  // namespace

std::vector<int> non_section_prisms(const Shell& shell, const SurfaceMesh& input) {
  const InputSurfaceIndex index(input.V, input.F, shell.reference);
  return scan_section(shell, index).failing;
}

ShellVerification verify_shell(const Shell& shell, const SurfaceMesh& input) {
  const auto t0 = std::chrono::steady_clock::now();
  ShellVerification r;
  if (shell.local_sheets && !shell.reference.empty())
    throw MeshingError("verify_shell: a locally injective shell with a reference copy");
  const int nf = int(shell.F.rows()), nv = int(shell.mid.rows());
  r.faces = nf;
  auto row = [](const Eigen::MatrixXd& M, int v) { return Eigen::Vector3d(M.row(v)); };

  // Positivity.
  for (int f = 0; f < nf; ++f) {
    std::array<Eigen::Vector3d, 3> b, m, t;
    std::array<bool, 3> s;
    for (int k = 0; k < 3; ++k) {
      const int v = shell.F(f, k);
      b[k] = row(shell.base, v);
      m[k] = row(shell.mid, v);
      t[k] = row(shell.top, v);
      s[k] = shell.singular[v];
    }
    if (!shell_face_positive(b, m, t, s)) ++r.non_positive_faces;
  }

  // The input (or its reference copy) for separation, the section and the distortion.
  const InputSurfaceIndex reference(input.V, input.F, shell.reference);

  // Separation, from the input side: an index over all base and top triangles. A singular
  // vertex carries its input vertex id in both, so contact there is recognized as a pinch;
  // every other cage vertex gets an id no input vertex has.
  {
    const int ni = input.num_vertices();
    Eigen::MatrixXd cage(2 * nv, 3);
    cage << shell.base, shell.top;
    Eigen::MatrixXd cage_v(ni + 2 * nv, 3);
    cage_v.topRows(ni) = input.V;
    cage_v.bottomRows(2 * nv) = cage;
    Eigen::MatrixXi cf(2 * nf, 3);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = shell.F(f, k);
        const bool pinch = shell.singular[v] && shell.input_vertex[v] >= 0;
        cf(f, k) = pinch ? shell.input_vertex[v] : ni + v;
        cf(nf + f, k) = pinch ? shell.input_vertex[v] : ni + nv + v;
      }
    const InputSurfaceIndex cage_index(cage_v, cf);
    std::vector<char> singular_input(ni, 0);
    for (int v = 0; v < nv; ++v)
      if (shell.singular[v] && shell.input_vertex[v] >= 0)
        singular_input[shell.input_vertex[v]] = 1;
    // Faces of the reference copy with a snapped corner, exactly against the cage triangles
    // near them; a pinch at one of their corners counts as a crossing (conservative).
    std::vector<char> moved(std::size_t(input.num_faces()), 0);
    for (int f : reference.moved_faces()) {
      moved[std::size_t(f)] = 1;
      const auto tri = reference.exact_face(f);
      Eigen::AlignedBox3d box;
      for (const auto& q : tri) box.extend(q.p);
      // The rounded corners are within an ulp of the exact ones.
      const double scale =
          std::max(box.min().cwiseAbs().maxCoeff(), box.max().cwiseAbs().maxCoeff());
      const Eigen::Vector3d pad = Eigen::Vector3d::Constant(1e-14 * scale + 1e-300);
      bool hit = false;
      for (int c : cage_index.faces_in_box(box.min() - pad, box.max() + pad)) {
        for (int k = 0; k < 3 && !hit; ++k)
          for (int j = 0; j < 3 && !hit; ++j) hit = cf(c, k) == input.F(f, j);
        if (!hit) hit = exact_triangles_meet(tri, cage_index.face_triangle(c));
        if (hit) break;
      }
      r.intersecting_input_faces += hit;
      r.reference_self_intersections += reference.face_self_intersects(f);
      // Flattened far below the input face (the simplifier's bound, measured here on its own).
      const Eigen::Vector3d a = input.V.row(input.F(f, 0)), b = input.V.row(input.F(f, 1)),
                            c = input.V.row(input.F(f, 2));
      const double area = (b - a).cross(c - a).norm(),
                   copy = (tri[1].p - tri[0].p).cross(tri[2].p - tri[0].p).norm();
      r.reference_collapsed_faces += area > 0 && copy < k_min_reference_area_ratio * area;
    }
    // Input face g as a triangle, with its corners at pinch points (singular shell vertices).
    auto input_face = [&](int g) {
      std::pair<std::array<Eigen::Vector3d, 3>, std::array<bool, 3>> out;
      for (int k = 0; k < 3; ++k) {
        out.first[std::size_t(k)] = input.V.row(input.F(g, k));
        out.second[std::size_t(k)] = singular_input[std::size_t(input.F(g, k))];
      }
      return out;
    };
    if (shell.local_sheets) {
      // Each base and top triangle against the input faces of its prism's local sheet only,
      // still from the input side (the input triangle queried against the cage triangle).
      // (`reference` is the input itself: a locally injective shell has no reference copy.)
      const LocalSheets sheets(reference);
      std::vector<std::vector<int>> hits(static_cast<std::size_t>(nf));  // per prism, merged below
      tbb::parallel_for(0, nf, [&](int f) {
        Eigen::AlignedBox3d box;
        for (const Eigen::MatrixXd* M : {&shell.base, &shell.mid, &shell.top})
          for (int k = 0; k < 3; ++k) box.extend(row(*M, shell.F(f, k)));
        for (int g : sheets.sheet({shell.face_parent[std::size_t(f)]}, box)) {
          const auto [tri, s] = input_face(g);
          const Eigen::Vector3i ids = input.F.row(g);
          if (cage_index.triangle_meets_face(tri, s, ids, f) ||
              cage_index.triangle_meets_face(tri, s, ids, nf + f))
            hits[std::size_t(f)].push_back(g);
        }
      });
      std::vector<char> hit(std::size_t(input.num_faces()), 0);  // distinct input faces
      for (const auto& h : hits)
        for (int g : h) hit[std::size_t(g)] = 1;
      r.intersecting_input_faces += int(std::count(hit.begin(), hit.end(), 1));
    }
    for (int f = 0; f < input.num_faces() && !shell.local_sheets; ++f) {
      if (moved[std::size_t(f)]) continue;
      const auto [tri, s] = input_face(f);
      if (cage_index.triangle_intersects(tri, s, Eigen::Vector3i(input.F.row(f))))
        ++r.intersecting_input_faces;
    }
  }

  // Section condition (the argument is in shell_intersection.cpp) and the distortion.
  {
    const SectionScan scan = scan_section(shell, reference);
    r.non_section_faces = int(scan.failing.size());
    for (double c : scan.min_cos) r.min_pillar_cos = std::min(r.min_pillar_cos, c);
  }

  // Roundtrip of every input vertex through P⁻¹ and P. A pinch point (an input vertex that is
  // a singular shell vertex, base = mid = top) is a zero-length fiber: P⁻¹ must give its corner
  // and P the vertex itself (thesis §4.2.5), as for any other vertex.
  {
    // With a reference copy, P⁻¹ takes the vertex's point of the copy and P returns the input's.
    const ShellProjection projection(shell, input);
    const double unit = bbox_longest_edge(input.V);
    // A locally injective shell's P⁻¹ needs the sheet: a face at the vertex names it (-1: the
    // vertex is in no face, nothing to map).
    std::vector<int> face_at(input.num_vertices(), -1);
    for (int f = 0; f < input.num_faces(); ++f)
      for (int k = 0; k < 3; ++k)
        if (face_at[input.F(f, k)] < 0) face_at[input.F(f, k)] = f;
    for (int v = 0; v < input.num_vertices(); ++v) {
      if (face_at[v] < 0) continue;
      const Eigen::Vector3d x = input.V.row(v);
      const Eigen::Vector3d at = projection.reference_vertices().row(v).transpose();
      const auto q =
          shell.local_sheets ? projection.unproject(at, face_at[v]) : projection.unproject(at);
      if (!q) {
        ++r.roundtrip_failures;
        continue;
      }
      const auto back = projection.project(*q);
      if (!back) {
        ++r.roundtrip_failures;
        continue;
      }
      const double error = (back->position - x).norm() / unit;
      r.roundtrip_max_error_rel = std::max(r.roundtrip_max_error_rel, error);
      // Far beyond rounding (the dev meshes' largest is 3e-10): the fiber through x meets the
      // input elsewhere first, so P is not the inverse of P⁻¹ there.
      if (error > k_roundtrip_miss_rel) ++r.roundtrip_failures;
    }
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace curvefem::meshing::shell
