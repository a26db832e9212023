#include "meshing/core/shell_fibers.hpp"

#include <cstring>
#include <string>

#include "meshing/core/error.hpp"

namespace curvefem {

void validate_structure(const ShellFibers& s, int input_vertices, int input_faces) {
  const auto fail = [](const std::string& what) { throw InputError("shell fibers: " + what); };
  const Eigen::Index nv = s.mid.rows();
  if (s.mid.cols() != 3 || s.base.rows() != nv || s.top.rows() != nv || s.base.cols() != 3 ||
      s.top.cols() != 3)
    fail("base, mid and top must be #V × 3 each");
  if (s.faces.rows() > 0 && s.faces.cols() != 3) fail("faces must be #F × 3");
  for (int f = 0; f < s.num_prisms(); ++f) {
    const Eigen::Vector3i F = s.faces.row(f);
    if (F.minCoeff() < 0 || F.maxCoeff() >= nv)
      fail("face " + std::to_string(f) + " has a vertex id outside 0.." + std::to_string(nv - 1));
    if (!(F[0] < F[1] && F[0] < F[2]))
      fail("face " + std::to_string(f) + " does not start at its smallest vertex id");
  }
  if (Eigen::Index(s.reference_vertices.size()) != s.reference_positions.rows() ||
      (s.reference_positions.rows() > 0 && s.reference_positions.cols() != 3))
    fail("reference_vertices and reference_positions differ in length");
  if (s.refined()) {
    const Eigen::Index nr = s.surface_faces.rows();
    if (s.surface_faces.cols() != 3 ||
        (s.surface_points.rows() > 0 && s.surface_points.cols() != 3))
      fail("surface_faces and surface_points must be #F × 3 and #added × 3");
    if (Eigen::Index(s.surface_parent.size()) != nr || s.surface_bary.rows() != nr ||
        s.surface_bary.cols() != 9)
      fail("surface_parent and surface_bary must have a row per refined face (bary: 9 columns)");
    if (input_vertices >= 0) {
      const int limit = input_vertices + int(s.surface_points.rows());
      if (s.surface_faces.minCoeff() < 0 || s.surface_faces.maxCoeff() >= limit)
        fail("a refined face has a vertex id outside 0.." + std::to_string(limit - 1));
    }
    for (const int t : s.surface_parent)
      if (t < 0 || (input_faces >= 0 && t >= input_faces))
        fail("a refined face's parent " + std::to_string(t) + " is no input face");
    // From here on the refined surface is the one the ids refer to.
    if (input_vertices >= 0) input_vertices += int(s.surface_points.rows());
    if (input_faces >= 0) input_faces = int(nr);
  }
  for (std::size_t i = 0; i < s.reference_vertices.size(); ++i) {
    const int v = s.reference_vertices[i];
    if (v < 0 || (input_vertices >= 0 && v >= input_vertices) ||
        (i > 0 && v <= s.reference_vertices[i - 1]))
      fail("reference vertex " + std::to_string(v) + " (entry " + std::to_string(i) +
           ") is out of range or out of order");
  }
  const std::size_t np = std::size_t(s.num_prisms());
  if (np == 0 && s.candidate_offsets.empty()) return;
  if (s.candidate_offsets.size() != np + 1 || s.candidate_offsets.front() != 0 ||
      std::size_t(s.candidate_offsets.back()) != s.candidate_faces.size())
    fail("candidate_offsets must have #prisms + 1 entries from 0 to #candidate_faces");
  for (std::size_t f = 0; f < np; ++f) {
    if (s.candidate_offsets[f + 1] < s.candidate_offsets[f])
      fail("candidate_offsets decrease at prism " + std::to_string(f));
    for (int i = s.candidate_offsets[f]; i < s.candidate_offsets[f + 1]; ++i) {
      const int t = s.candidate_faces[std::size_t(i)];
      if (t < 0 || (input_faces >= 0 && t >= input_faces))
        fail("prism " + std::to_string(f) + " names input face " + std::to_string(t) +
             (input_faces >= 0 ? " of " + std::to_string(input_faces) : std::string()));
    }
  }
}

namespace {
template <class M>
bool same_bits(const M& a, const M& b) {
  if (a.size() == 0 && b.size() == 0) return true;  // 0 × 3 and 0 × 0 hold the same nothing
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(typename M::Scalar) * std::size_t(a.size())) == 0;
}
}  // namespace

bool identical(const ShellFibers& a, const ShellFibers& b) {
  return same_bits(a.base, b.base) && same_bits(a.mid, b.mid) && same_bits(a.top, b.top) &&
         same_bits(a.faces, b.faces) && a.reference_vertices == b.reference_vertices &&
         same_bits(a.reference_positions, b.reference_positions) &&
         a.candidate_offsets == b.candidate_offsets && a.candidate_faces == b.candidate_faces &&
         same_bits(a.surface_points, b.surface_points) &&
         same_bits(a.surface_faces, b.surface_faces) && a.surface_parent == b.surface_parent &&
         same_bits(a.surface_bary, b.surface_bary);
}

}  // namespace curvefem
