#include "meshing/shell/local_sheets.hpp"

#include <algorithm>
#include <cstdint>

namespace curvefem::meshing::shell {

LocalSheets::LocalSheets(const InputSurfaceIndex& index)
    : m_index(index), m_vertex_faces(std::size_t(index.V().rows())) {
  const Eigen::MatrixXi& F = index.F();
  for (int f = 0; f < int(F.rows()); ++f)
    for (int k = 0; k < 3; ++k) m_vertex_faces[std::size_t(F(f, k))].push_back(f);
}

std::vector<int> LocalSheets::sheet(const std::vector<int>& seeds,
                                    const Eigen::AlignedBox3d& box) const {
  // Per-thread face marks stamped with a generation that is new for every call: no clearing,
  // and no search per step (this runs for every prism checked).
  struct Marks {
    std::vector<std::uint32_t> in_box, reached;
    std::uint32_t generation = 0;
  };
  thread_local Marks marks;
  const std::size_t nf = std::size_t(m_index.F().rows());
  if (marks.in_box.size() < nf) {
    marks.in_box.assign(nf, 0);
    marks.reached.assign(nf, 0);
  }
  if (++marks.generation == 0) {  // wrapped: start over
    std::fill(marks.in_box.begin(), marks.in_box.end(), 0);
    std::fill(marks.reached.begin(), marks.reached.end(), 0);
    marks.generation = 1;
  }
  const std::uint32_t g = marks.generation;
  for (int f : m_index.faces_in_box(box.min(), box.max())) marks.in_box[std::size_t(f)] = g;
  std::vector<int> out, stack;
  auto reach = [&](int f) {
    if (f < 0 || std::size_t(f) >= nf || marks.in_box[std::size_t(f)] != g ||
        marks.reached[std::size_t(f)] == g)
      return;
    marks.reached[std::size_t(f)] = g;
    out.push_back(f);
    stack.push_back(f);
  };
  for (int f : seeds) reach(f);
  const Eigen::MatrixXi& F = m_index.F();
  while (!stack.empty()) {
    const int f = stack.back();
    stack.pop_back();
    for (int k = 0; k < 3; ++k)
      for (int h : m_vertex_faces[std::size_t(F(f, k))]) reach(h);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace curvefem::meshing::shell
