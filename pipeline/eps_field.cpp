#include "pipeline/eps_field.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "meshing/core/error.hpp"
#include "pipeline/expression.hpp"

namespace curvefem::pipeline {

std::vector<double> eps_scale_from_expression(const SurfaceMesh& input, const std::string& field,
                                              double eps_rel, const std::string& where) {
  if (!(eps_rel > 0)) throw InputError(where + ": eps must be positive");
  const Expression e(field, where);
  std::vector<double> scale(std::size_t(input.num_vertices()));
  for (int v = 0; v < input.num_vertices(); ++v) {
    const Eigen::Vector3d x = input.V.row(v).transpose();
    const double value = e(x);
    if (!(value > 0) || !std::isfinite(value)) {
      std::ostringstream msg;
      msg << where << ": the eps field \"" << field << "\" is " << value << " at input vertex " << v
          << " (" << x.x() << ", " << x.y() << ", " << x.z() << "); it must be a positive bound";
      throw InputError(msg.str());
    }
    scale[std::size_t(v)] = std::min(value, eps_rel) / eps_rel;
  }
  return scale;
}

}  // namespace curvefem::pipeline
