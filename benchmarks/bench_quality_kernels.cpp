// Per-call cost of the curved-tet quality kernels the mesher's optimization, edits and validator
// call for every candidate cell: cell_energy (conformal AMIPS over the order-k lattice),
// min_scaled_jacobian (over the det J lattice and the four corner frames), curved_mips (56
// points) and certify_tet_jacobian. Valid curved tets (straight tets of random shape with nodes
// moved by up to 0.4% of the reference size), orders 1..4. Only public API, so the same file
// builds against older revisions for before/after figures.
//   cmake --build build --target curvefem_bench_quality_kernels
//   build/benchmarks/curvefem_bench_quality_kernels [calls per kernel and order, default 20000]
#include <Eigen/LU>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/curved/optimize.hpp"

using namespace curvefem;
using namespace curvefem::meshing::curved;

int main(int argc, char** argv) {
  const int calls = argc > 1 ? std::atoi(argv[1]) : 20000;
  std::printf("| K | cell_energy us | min_scaled_jacobian us | curved_mips us | certify us |\n");
  std::printf("|---|---|---|---|---|\n");
  for (int k = 1; k <= 4; ++k) {
    const Eigen::MatrixXd ref = lagrange_reference_nodes(CellKind::tetrahedron, k);
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> shape(-0.3, 0.3), bump(-0.004, 0.004);
    std::vector<Eigen::MatrixXd> tets;
    for (int i = 0; i < 200; ++i) {
      Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
      for (int e = 0; e < 9; ++e) A(e / 3, e % 3) += shape(rng);
      if (A.determinant() < 0.2) continue;
      Eigen::MatrixXd x = ref * A.transpose();
      for (Eigen::Index r = 0; r < x.rows(); ++r)
        for (int c = 0; c < 3; ++c) x(r, c) += bump(rng);
      tets.push_back(x);
    }
    double sink = 0;
    auto per_call = [&](auto&& kernel) {
      for (const Eigen::MatrixXd& x : tets) sink += kernel(x);  // tables built, caches warm
      const auto t0 = std::chrono::steady_clock::now();
      for (int i = 0; i < calls; ++i) sink += kernel(tets[std::size_t(i) % tets.size()]);
      return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                 .count() /
             calls;
    };
    const double e = per_call([&](const Eigen::MatrixXd& x) { return cell_energy(k, x); });
    const double s = per_call([&](const Eigen::MatrixXd& x) { return min_scaled_jacobian(k, x); });
    const double m = per_call([&](const Eigen::MatrixXd& x) { return curved_mips(k, x); });
    const double c = per_call([&](const Eigen::MatrixXd& x) {
      return double(certify_tet_jacobian(k, x).verdict == JacobianVerdict::positive);
    });
    std::printf("| %d | %.2f | %.2f | %.2f | %.2f |\n", k, e, s, m, c);
    if (sink == 42.0) std::printf(" ");  // keeps the calls
  }
}
