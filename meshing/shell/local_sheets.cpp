#include "meshing/shell/local_sheets.hpp"

#include <algorithm>

namespace curvefem::meshing::shell {

LocalSheets::LocalSheets(const InputSurfaceIndex& index)
    : m_index(index), m_vertex_faces(std::size_t(index.V().rows())) {
  const Eigen::MatrixXi& F = index.F();
  for (int f = 0; f < int(F.rows()); ++f)
    for (int k = 0; k < 3; ++k) m_vertex_faces[std::size_t(F(f, k))].push_back(f);
}

std::vector<int> LocalSheets::sheet(const std::vector<int>& seeds,
                                    const Eigen::AlignedBox3d& box) const {
  // Candidates: the faces whose box meets `box` (sorted); a face is stepped on once.
  std::vector<int> candidates = m_index.faces_in_box(box.min(), box.max());
  std::sort(candidates.begin(), candidates.end());
  std::vector<char> reached(candidates.size(), 0);
  auto slot = [&](int f) -> long {
    const auto it = std::lower_bound(candidates.begin(), candidates.end(), f);
    return it != candidates.end() && *it == f ? long(it - candidates.begin()) : -1;
  };
  std::vector<int> stack;
  for (int f : seeds)
    if (const long i = slot(f); i >= 0 && !reached[std::size_t(i)]) {
      reached[std::size_t(i)] = 1;
      stack.push_back(f);
    }
  const Eigen::MatrixXi& F = m_index.F();
  while (!stack.empty()) {
    const int f = stack.back();
    stack.pop_back();
    for (int k = 0; k < 3; ++k)
      for (int g : m_vertex_faces[std::size_t(F(f, k))])
        if (const long i = slot(g); i >= 0 && !reached[std::size_t(i)]) {
          reached[std::size_t(i)] = 1;
          stack.push_back(g);
        }
  }
  std::vector<int> out;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (reached[i]) out.push_back(candidates[i]);
  return out;
}

}  // namespace curvefem::meshing::shell
