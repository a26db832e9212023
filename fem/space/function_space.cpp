#include "fem/space/function_space.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/morton.hpp"

namespace curvefem::fem {
namespace {

struct DofKey {
  std::array<int, 4> vertex{-1, -1, -1, -1};
  std::array<int, 4> weight{0, 0, 0, 0};
  bool operator==(const DofKey&) const = default;
};

struct DofKeyHash {
  std::size_t operator()(const DofKey& k) const {
    std::size_t h = 1469598103934665603ull;
    for (int i = 0; i < 4; ++i) {
      h = (h ^ static_cast<std::size_t>(k.vertex[i] + 1)) * 1099511628211ull;
      h = (h ^ static_cast<std::size_t>(k.weight[i])) * 1099511628211ull;
    }
    return h;
  }
};

// Cells in Morton (Z-curve) order of their corner centroids: numbering the DOFs in this order,
// rather than in the mesh file's cell order (Gmsh's is spatially random), gives neighbouring DOFs
// neighbouring numbers, so element scatters, sparse products and the AMG setup touch memory
// locally. Only the numbering changes; the space is the same.
std::vector<int> spatial_cell_order(const LagrangeMesh& mesh) {
  const int nc = mesh.num_cells();
  std::vector<int> order(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) order[static_cast<std::size_t>(c)] = c;
  if (nc == 0) return order;
  Eigen::MatrixXd centroid(nc, 3);
  for (int c = 0; c < nc; ++c) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int i = 0; i < 4; ++i) sum += mesh.nodes.row(mesh.cells(c, i));
    centroid.row(c) = sum / 4;
  }
  const Eigen::Vector3d lo = centroid.colwise().minCoeff().transpose();
  const double extent =
      std::max((centroid.colwise().maxCoeff().transpose() - lo).maxCoeff(), 1e-300);
  std::vector<std::uint64_t> key(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c)
    key[static_cast<std::size_t>(c)] = morton_key(centroid.row(c).transpose(), lo, extent);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return key[std::size_t(a)] != key[std::size_t(b)] ? key[std::size_t(a)] < key[std::size_t(b)]
                                                      : a < b;
  });
  return order;
}

struct FaceKeyHash {
  std::size_t operator()(const std::array<int, 3>& f) const {
    return (static_cast<std::size_t>(f[0]) * 73856093u) ^
           (static_cast<std::size_t>(f[1]) * 19349663u) ^
           (static_cast<std::size_t>(f[2]) * 83492791u);
  }
};

}  // namespace

std::vector<BoundaryFace> find_boundary_faces(const LagrangeMesh& mesh) {
  std::unordered_map<std::array<int, 3>, std::pair<int, int>, FaceKeyHash> count;  // → (n, first)
  count.reserve(static_cast<std::size_t>(mesh.num_cells()) * 2);
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int j = 0; j < 4; ++j) {
      std::array<int, 3> f;
      int n = 0;
      for (int i = 0; i < 4; ++i)
        if (i != j) f[n++] = mesh.cells(c, i);
      std::sort(f.begin(), f.end());
      auto [it, inserted] = count.try_emplace(f, 0, 4 * c + j);
      it->second.first++;
    }
  std::vector<BoundaryFace> faces;
  for (const auto& [key, value] : count) {
    if (value.first > 2)
      throw InputError("non-manifold tetrahedral mesh: a face is shared by " +
                           std::to_string(value.first) + " cells",
                       {.element = value.second / 4});
    if (value.first == 1) faces.push_back({value.second / 4, value.second % 4});
  }
  std::sort(faces.begin(), faces.end(), [](const BoundaryFace& a, const BoundaryFace& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.opposite < b.opposite;
  });
  return faces;
}

FunctionSpace build_function_space(const LagrangeMesh& mesh, int degree) {
  if (mesh.kind != CellKind::tetrahedron) throw InputError("function space needs tetrahedra");
  if (degree < 1 || degree > 4)
    throw InputError("polynomial degree " + std::to_string(degree) + " is not in 1..4");
  validate_structure(mesh);
  FunctionSpace space;
  space.degree = degree;
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, degree);
  const int n = static_cast<int>(lattice.size());
  space.cell_dofs.resize(mesh.num_cells(), n);
  std::unordered_map<DofKey, int, DofKeyHash> ids;
  ids.reserve(static_cast<std::size_t>(mesh.num_cells()) * n / 4);
  std::vector<std::pair<int, int>> first_seen;  // dof → (cell, local)
  for (const int c : spatial_cell_order(mesh)) {
    for (int l = 0; l < n; ++l) {
      std::array<std::pair<int, int>, 4> entries;
      int m = 0;
      for (int i = 0; i < 4; ++i)
        if (lattice[l][i] > 0) entries[m++] = {mesh.cells(c, i), lattice[l][i]};
      for (int a = 1; a < m; ++a)  // insertion sort of at most 4 entries
        for (int b = a; b > 0 && entries[b] < entries[b - 1]; --b)
          std::swap(entries[b], entries[b - 1]);
      DofKey key;
      for (int i = 0; i < m; ++i)
        key.vertex[i] = entries[i].first, key.weight[i] = entries[i].second;
      auto [it, inserted] = ids.try_emplace(key, static_cast<int>(first_seen.size()));
      if (inserted) first_seen.emplace_back(c, l);
      space.cell_dofs(c, l) = it->second;
    }
  }
  space.num_dofs = static_cast<int>(first_seen.size());
  const Eigen::MatrixXd ref = lagrange_reference_nodes(CellKind::tetrahedron, degree);
  space.dof_points.resize(space.num_dofs, 3);
  for (int d = 0; d < space.num_dofs; ++d) {
    const auto [c, l] = first_seen[d];
    space.dof_points.row(d) = mesh.map(c, ref.row(l).transpose()).transpose();
  }
  space.boundary_faces = find_boundary_faces(mesh);
  space.on_boundary.assign(space.num_dofs, 0);
  for (const auto& f : space.boundary_faces)
    for (int l = 0; l < n; ++l)
      if (lattice[l][f.opposite] == 0) space.on_boundary[space.cell_dofs(f.cell, l)] = 1;
  return space;
}

}  // namespace curvefem::fem
