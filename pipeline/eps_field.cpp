#include "pipeline/eps_field.hpp"

#include <algorithm>
#include <cmath>
#include <set>
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

std::vector<double> eps_scale_from_tags(const SurfaceMesh& input,
                                        const std::map<std::string, double>& by_tag, double eps_rel,
                                        const std::string& where) {
  if (!(eps_rel > 0)) throw InputError(where + ": eps must be positive");
  if (by_tag.empty()) return {};
  if (!input.has_tags())
    throw InputError(where +
                     ": the input surface has no face tags (OBJ groups, a PLY face property or "
                     "MSH physical groups name them)");
  std::set<int> present(input.tags.data(), input.tags.data() + input.tags.size());
  std::map<int, double> bound;  // tag -> relative bound
  for (const auto& [key, value] : by_tag) {
    const std::string at = where + "/" + key;
    if (!(value > 0 && value <= 0.5)) {
      std::ostringstream msg;
      msg << at << ": " << value << " is not a bound in (0, 0.5]";
      throw InputError(msg.str());
    }
    int tag = 0;
    bool found = false;
    for (const auto& [t, name] : input.tag_names)
      if (name == key) tag = t, found = true;
    if (!found) {
      std::size_t used = 0;
      try {
        tag = std::stoi(key, &used);
        found = used == key.size() && present.count(tag) > 0;
      } catch (const std::exception&) {
        found = false;
      }
    }
    if (!found) {
      std::ostringstream msg;
      msg << at << ": the input has no face tag \"" << key << "\"; its tags are";
      for (int t : present) {
        msg << " " << t;
        if (auto it = input.tag_names.find(t); it != input.tag_names.end())
          msg << " (" << it->second << ")";
      }
      throw InputError(msg.str());
    }
    bound[tag] = value;
  }
  std::vector<double> scale(std::size_t(input.num_vertices()), 1.0);
  for (int f = 0; f < input.num_faces(); ++f) {
    const auto it = bound.find(input.tags[f]);
    if (it == bound.end()) continue;
    const double s = std::min(it->second, eps_rel) / eps_rel;
    for (int c = 0; c < 3; ++c) {
      double& v = scale[std::size_t(input.F(f, c))];
      v = std::min(v, s);
    }
  }
  return scale;
}

std::vector<double> min_eps_scale(std::vector<double> a, const std::vector<double>& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) a[i] = std::min(a[i], b[i]);
  return a;
}

}  // namespace curvefem::pipeline
