#pragma once
// Feature edges of a dense input surface (thesis §5.2.2; reference-notes §3.7): given as
// vertex-index pairs, or detected where the dihedral angle between the two faces of an edge —
// the angle between their normals — exceeds a threshold.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::curved {

// Edges (a < b) whose two faces' normals make an angle above `angle_deg` degrees; sorted.
std::vector<std::array<int, 2>> detect_feature_edges(const SurfaceMesh& mesh, double angle_deg);

// `edges` without the connected components (edges sharing a vertex) whose bounding box has a
// diagonal below `min_extent` × the smallest `scale` at their vertices (scale empty: 1): curves
// smaller than the distance bound — a small hole's rim, a crease of two tessellation slivers —
// that a coarse surface could follow only with elements of their size. Sorted like `edges`;
// `dropped_components`, if given, receives how many components were left out.
std::vector<std::array<int, 2>> drop_small_feature_components(
    const SurfaceMesh& mesh, const std::vector<std::array<int, 2>>& edges, double min_extent,
    const std::vector<double>& scale = {}, int* dropped_components = nullptr);

// `edges` with the open ends of feature curves cut back: from every vertex with one feature edge,
// edges are removed along the curve until the removed arc length reaches `length` × the `scale`
// at that end vertex (scale empty: 1) or a vertex where curves meet (a spur shorter than that
// goes whole). A curve that fades out on a CAD part (a crease becoming a fillet) ends in a
// frozen corner, and where that end stops a fraction of ε short of another curve the coarse
// surface keeps a cap between them (tr12j_occt: an end 0.1 ε from a crease, a coarse face of
// 175°). Closed curves and curves between junctions are untouched. Sorted like `edges`;
// `trimmed_ends`, if given, receives how many ends were cut.
std::vector<std::array<int, 2>> trim_feature_ends(const SurfaceMesh& mesh,
                                                  const std::vector<std::array<int, 2>>& edges,
                                                  double length,
                                                  const std::vector<double>& scale = {},
                                                  int* trimmed_ends = nullptr);

// Throws InputError naming the pair if an edge is not an edge of the mesh; returns the edges
// sorted with a < b and without duplicates.
std::vector<std::array<int, 2>> validate_feature_edges(const SurfaceMesh& mesh,
                                                       std::vector<std::array<int, 2>> edges);

// #V flags: endpoints of feature edges.
std::vector<char> feature_vertices(int num_vertices, const std::vector<std::array<int, 2>>& edges);

}  // namespace curvefem::meshing::curved
