#include "meshing/shell/section_transfer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/shell/shell_geometry.hpp"

namespace curvefem::meshing::shell {

Eigen::MatrixXd transfer_vertex_field(const ShellProjection& onto_source, const SurfaceMesh& source,
                                      const Eigen::MatrixXd& values, const Eigen::MatrixXd& points,
                                      int* failures) {
  CF_VERIFY(values.rows() == source.num_vertices(), "one field value row per source vertex");
  Eigen::MatrixXd out = Eigen::MatrixXd::Constant(points.rows(), values.cols(),
                                                  std::numeric_limits<double>::quiet_NaN());
  int failed = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const auto q = onto_source.locate(points.row(i).transpose());
    const auto s = q ? onto_source.project(*q) : std::nullopt;
    if (!s) {
      ++failed;
      continue;
    }
    out.row(i).setZero();
    for (int k = 0; k < 3; ++k) out.row(i) += s->bary[k] * values.row(source.F(s->face, k));
  }
  if (failures != nullptr) *failures = failed;
  return out;
}

namespace {
// r.back against values over the referenced input vertices: max and mean of the per-vertex max
// error; a vertex whose value did not come back (NaN) is a failure.
void count_roundtrip_errors(const SurfaceMesh& input, const Eigen::MatrixXd& values,
                            FieldRoundtrip& r) {
  std::vector<char> referenced(std::size_t(input.num_vertices()), 0);
  for (int f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) referenced[std::size_t(input.F(f, k))] = 1;
  double sum = 0;
  int count = 0;
  for (int v = 0; v < input.num_vertices(); ++v) {
    if (!referenced[std::size_t(v)]) continue;
    const double e = (r.back.row(v) - values.row(v)).cwiseAbs().maxCoeff();
    if (!std::isfinite(e)) {
      ++r.failures;
      continue;
    }
    r.max_error = std::max(r.max_error, e);
    sum += e;
    ++count;
  }
  r.mean_error = count > 0 ? sum / count : 0.0;
}
}  // namespace

FieldRoundtrip field_roundtrip(const ShellProjection& onto_input, const SurfaceMesh& input,
                               const SurfaceMesh& section, const Eigen::MatrixXd& values) {
  FieldRoundtrip r;
  r.there = transfer_vertex_field(onto_input, input, values, section.V, &r.failures);
  const ShellProjection onto_section(onto_input.shell(), section);
  r.back = transfer_vertex_field(onto_section, section, r.there, input.V);
  count_roundtrip_errors(input, values, r);
  return r;
}

FieldRoundtrip middle_field_roundtrip(const ShellProjection& onto_input, const SurfaceMesh& input,
                                      const Eigen::MatrixXd& values) {
  const Shell& shell = onto_input.shell();
  const int nm = int(shell.mid.rows()), k = int(values.cols());
  FieldRoundtrip r;
  r.there = Eigen::MatrixXd::Constant(nm, k, std::numeric_limits<double>::quiet_NaN());
  // A middle vertex: corner c of an incident face in the rotated order P's coordinates use.
  std::vector<char> done(std::size_t(nm), 0);
  for (int f = 0; f < shell.F.rows(); ++f) {
    const Eigen::Vector3i F = shell.F.row(f);
    const int rot = min_rotation(F);
    for (int c = 0; c < 3; ++c) {
      const int v = F[(rot + c) % 3];
      if (done[std::size_t(v)]) continue;
      done[std::size_t(v)] = 1;
      const auto hit =
          onto_input.project(PrismPoint{f, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0, 0.0});
      if (!hit) {
        ++r.failures;
        continue;
      }
      Eigen::RowVectorXd value = Eigen::RowVectorXd::Zero(k);
      for (int j = 0; j < 3; ++j) value += hit->bary[j] * values.row(input.F(hit->face, j));
      r.there.row(v) = value;
    }
  }
  // An input vertex: through a face at it.
  std::vector<int> face_at(std::size_t(input.num_vertices()), -1);
  for (int f = 0; f < input.num_faces(); ++f)
    for (int j = 0; j < 3; ++j)
      if (face_at[std::size_t(input.F(f, j))] < 0) face_at[std::size_t(input.F(f, j))] = f;
  r.back =
      Eigen::MatrixXd::Constant(input.num_vertices(), k, std::numeric_limits<double>::quiet_NaN());
  for (int x = 0; x < input.num_vertices(); ++x) {
    const int g = face_at[std::size_t(x)];
    if (g < 0) continue;
    const auto q = onto_input.unproject(onto_input.reference_vertices().row(x).transpose(), g);
    if (!q) continue;  // stays NaN: a failure
    const Eigen::Vector3i F = shell.F.row(q->face);
    const int rot = min_rotation(F);
    const double w[3] = {1 - q->u - q->v, q->u, q->v};
    Eigen::RowVectorXd value = Eigen::RowVectorXd::Zero(k);
    for (int c = 0; c < 3; ++c) value += w[c] * r.there.row(F[(rot + c) % 3]);
    r.back.row(x) = value;
  }
  count_roundtrip_errors(input, values, r);
  return r;
}

Eigen::VectorXd smooth_test_field(const Eigen::MatrixXd& V, const Eigen::Vector3d& center,
                                  double scale) {
  Eigen::VectorXd f(V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const Eigen::Vector3d p = (V.row(i).transpose() - center) / scale;
    f[i] = std::sin(3 * p.x()) * std::cos(2 * p.y()) + p.z() * p.z();
  }
  return f;
}

}  // namespace curvefem::meshing::shell
