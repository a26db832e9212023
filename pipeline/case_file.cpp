#include "pipeline/case_file.hpp"

#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "meshing/core/error.hpp"
#include "pipeline/case_schema.hpp"

namespace curvefem::pipeline {
namespace {

using json = nlohmann::json;

[[noreturn]] void fail(const std::string& path, const std::string& what, const std::string& file) {
  throw InputError((path.empty() ? std::string("/") : path) + ": " + what, {.file = file});
}

/// An expression value as resolved_case.json writes it: a number becomes its text (17 digits, as
/// Reader::expression reads it), arrays element by element; anything else is left to the parser.
json expression_text(const json& v) {
  if (v.is_number()) {
    std::ostringstream s;
    s.precision(17);
    s << v.get<double>();
    return s.str();
  }
  if (!v.is_array()) return v;
  json out = json::array();
  for (const json& e : v) out.push_back(expression_text(e));
  return out;
}

struct Reader {
  std::string file;

  /// The keys of the object `j` (at JSON path `path`) must be children of the schema path
  /// `section` (case_schema.hpp): a key is accepted only if the schema has a row for it.
  void only_keys(const json& j, const std::string& path, std::string_view section) const {
    if (!j.is_object()) fail(path, "expected an object", file);
    const std::set<std::string> allowed = case_section_keys(section);
    for (const auto& [key, value] : j.items())
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(path + "/" + key, "unknown key (allowed here: " + list + ")", file);
      }
  }
  const json* get(const json& j, const std::string& key) const {
    auto it = j.find(key);
    return it == j.end() ? nullptr : &*it;
  }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, "expected a string", file);
    return j.get<std::string>();
  }
  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, "expected a number", file);
    return j.get<double>();
  }
  int integer(const json& j, const std::string& path, int lo, int hi) const {
    if (!j.is_number_integer()) fail(path, "expected an integer", file);
    const long long v = j.get<long long>();
    if (v < lo || v > hi)
      fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi), file);
    return static_cast<int>(v);
  }
  /// An expression: a string or a number; `normal`: whether nx, ny, nz may appear.
  Expression expression(const json& j, const std::string& path, bool normal = false) const {
    if (j.is_number()) return Expression(expression_text(j).get<std::string>(), path);
    if (!j.is_string()) fail(path, "expected an expression (string or number)", file);
    try {
      return Expression(j.get<std::string>(), path, normal);
    } catch (const InputError& e) {
      throw InputError(e.defect(), {.file = file});
    }
  }
  /// One expression (scalar problems) or an array of three (vector problems).
  std::vector<Expression> expressions(const json& j, const std::string& path, int components,
                                      bool normal = false) const {
    std::vector<Expression> out;
    if (components == 1) {
      if (j.is_array()) fail(path, "expected one expression (scalar problem)", file);
      out.push_back(expression(j, path, normal));
      return out;
    }
    if (!j.is_array() || j.size() != 3)
      fail(path, "expected an array of three expressions (vector problem)", file);
    for (int i = 0; i < 3; ++i)
      out.push_back(expression(j[i], path + "/" + std::to_string(i), normal));
    return out;
  }
  /// A string that must be one of the allowed values of the schema key `key`.
  std::string choice(const json& j, const std::string& path, std::string_view key) const {
    std::string s = string(j, path);
    const CaseKey& k = case_key(key);
    CF_VERIFY(!k.allowed.empty(), "schema key without allowed values");
    if (std::find(k.allowed.begin(), k.allowed.end(), s) != k.allowed.end()) return s;
    std::string list;
    for (std::size_t i = 0; i < k.allowed.size(); ++i)
      list += (i == 0 ? "" : i + 1 == k.allowed.size() ? " or " : ", ") + std::string(k.allowed[i]);
    fail(path, "'" + s + "': expected " + list, file);
  }
  /// The enum value of a choice (the schema's allowed spellings are the enum's).
  template <class E>
  E choice_of(const json& j, const std::string& path, std::string_view key) const {
    return enum_from<E>(choice(j, path, key));
  }
  /// An integer in the schema key's range.
  int integer(const json& j, const std::string& path, std::string_view key) const {
    const CaseKey& k = case_key(key);
    CF_VERIFY(k.range && std::isfinite(k.range->lo) && std::isfinite(k.range->hi),
              "schema key without an integer range");
    return integer(j, path, static_cast<int>(k.range->lo), static_cast<int>(k.range->hi));
  }
  /// A number in the schema key's range.
  double number(const json& j, const std::string& path, std::string_view key) const {
    const double v = number(j, path);
    in_range(v, path, key);
    return v;
  }
  void in_range(double v, const std::string& path, std::string_view key) const {
    const CaseKey& k = case_key(key);
    CF_VERIFY(k.range.has_value(), "schema key without a range");
    if (k.range->contains(v)) return;
    const CaseKeyRange& r = *k.range;
    std::string what;
    if (r.lo == 0 && r.lo_open && !std::isfinite(r.hi))
      what = "must be positive";
    else if (std::isfinite(r.lo) && std::isfinite(r.hi))
      what = "must be in " + r.text(false);
    else
      what = "must be " + r.text(false);
    fail(path, what + std::string(k.range_note), file);
  }
  Eigen::Vector3d point(const json& j, const std::string& path) const {
    if (!j.is_array() || j.size() != 3) fail(path, "expected [x, y, z]", file);
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) p[i] = number(j[i], path + "/" + std::to_string(i));
    return p;
  }
};

Eigen::Vector3d nonzero_vector(const Reader& r, const json& j, const std::string& path) {
  const Eigen::Vector3d d = r.point(j, path);
  if (!(d.norm() > 0)) fail(path, "must be a non-zero vector", r.file);
  return d;
}

Selection read_selection(const Reader& r, const json& j, const std::string& path) {
  const char* k_kinds = "all, tag, box, plane, normal, and, or, not, outer_box";
  r.only_keys(j, path, "boundary_conditions[].select");
  if (j.size() != 1) fail(path, std::string("a selection has exactly one of: ") + k_kinds, r.file);
  Selection s;
  s.where = path;
  if (const json* v = r.get(j, "all")) {
    if (!v->is_boolean() || !v->get<bool>()) fail(path + "/all", "expected true", r.file);
    s.kind = Selection::Kind::all;
  } else if (const json* v = r.get(j, "tag")) {
    s.kind = Selection::Kind::tag;
    s.tag = r.integer(*v, path + "/tag", "boundary_conditions[].select.tag");
  } else if (const json* v = r.get(j, "box")) {
    s.kind = Selection::Kind::box;
    if (!v->is_array() || v->size() != 2)
      fail(path + "/box", "expected [[x0,y0,z0],[x1,y1,z1]]", r.file);
    s.lo = r.point((*v)[0], path + "/box/0");
    s.hi = r.point((*v)[1], path + "/box/1");
    if ((s.lo.array() > s.hi.array()).any())
      fail(path + "/box", "lower corner above upper corner", r.file);
  } else if (const json* v = r.get(j, "plane")) {
    s.kind = Selection::Kind::plane;
    const std::string p = path + "/plane";
    r.only_keys(*v, p, "boundary_conditions[].select.plane");
    const json* point = r.get(*v, "point");
    const json* normal = r.get(*v, "normal");
    if (!point) fail(p + "/point", "missing ([x, y, z] on the plane)", r.file);
    if (!normal) fail(p + "/normal", "missing ([nx, ny, nz], towards the selected side)", r.file);
    s.point = r.point(*point, p + "/point");
    s.direction = nonzero_vector(r, *normal, p + "/normal");
  } else if (const json* v = r.get(j, "normal")) {
    s.kind = Selection::Kind::normal;
    const std::string p = path + "/normal";
    r.only_keys(*v, p, "boundary_conditions[].select.normal");
    const json* dir = r.get(*v, "direction");
    if (!dir) fail(p + "/direction", "missing ([dx, dy, dz])", r.file);
    s.direction = nonzero_vector(r, *dir, p + "/direction");
    if (const json* a = r.get(*v, "angle"))
      s.angle_deg = r.number(*a, p + "/angle", "boundary_conditions[].select.normal.angle");
  } else if (const json* v = r.get(j, "outer_box")) {
    s.kind = Selection::Kind::outer_box;
    const std::string side =
        r.choice(*v, path + "/outer_box", "boundary_conditions[].select.outer_box");
    s.box_side = -2;
    for (int i = -1; i < 6; ++i)
      if (side == mapping::box_side_name(i)) s.box_side = i;
    CF_VERIFY(s.box_side != -2, "outer_box side in the schema but not in mapping/selection");
  } else if (const json* v = r.get(j, "not")) {
    s.kind = Selection::Kind::none_of;
    s.children.push_back(read_selection(r, *v, path + "/not"));
  } else {
    const bool is_and = r.get(j, "and") != nullptr;
    const std::string key = is_and ? "and" : "or";
    const json& list = *r.get(j, key);
    s.kind = is_and ? Selection::Kind::all_of : Selection::Kind::any_of;
    if (!list.is_array() || list.empty())
      fail(path + "/" + key, "expected a non-empty array of selections", r.file);
    for (std::size_t i = 0; i < list.size(); ++i)
      s.children.push_back(read_selection(r, list[i], path + "/" + key + "/" + std::to_string(i)));
  }
  return s;
}

json selection_json(const Selection& s) {
  auto vec = [](const Eigen::Vector3d& v) { return json::array({v[0], v[1], v[2]}); };
  switch (s.kind) {
    case Selection::Kind::all:
      return {{"all", true}};
    case Selection::Kind::tag:
      return {{"tag", s.tag}};
    case Selection::Kind::box:
      return {{"box", json::array({vec(s.lo), vec(s.hi)})}};
    case Selection::Kind::plane:
      return {{"plane", {{"point", vec(s.point)}, {"normal", vec(s.direction)}}}};
    case Selection::Kind::normal:
      return {{"normal", {{"direction", vec(s.direction)}, {"angle", s.angle_deg}}}};
    case Selection::Kind::outer_box:
      return {{"outer_box", mapping::box_side_name(s.box_side)}};
    case Selection::Kind::none_of:
      return {{"not", selection_json(s.children.at(0))}};
    case Selection::Kind::all_of:
    case Selection::Kind::any_of: {
      json list = json::array();
      for (const auto& c : s.children) list.push_back(selection_json(c));
      return {{s.kind == Selection::Kind::all_of ? "and" : "or", list}};
    }
  }
  return {};
}

/// The load part of a case (rhs, exact, exact_gradient, boundary_conditions) from the object `o`
/// at JSON path `pre` (the case itself, or one of its load_cases).
LoadCase read_load(const Reader& r, const json& o, const std::string& pre, const CaseSpec& c) {
  const int comps = c.components();
  LoadCase l;
  if (const json* v = r.get(o, "rhs")) l.rhs = r.expressions(*v, pre + "/rhs", comps);
  // A zero body load (the default) is no body load: nothing to assemble.
  if (std::all_of(l.rhs.begin(), l.rhs.end(), [](const Expression& e) {
        const auto value = e.constant();
        return value && *value == 0.0;
      }))
    l.rhs.clear();
  if (const json* v = r.get(o, "exact")) l.exact = r.expressions(*v, pre + "/exact", comps);
  if (const json* v = r.get(o, "exact_gradient")) {
    if (comps == 1) {
      l.exact_gradient = r.expressions(*v, pre + "/exact_gradient", 3);
    } else {
      if (!v->is_array() || v->size() != 3)
        fail(pre + "/exact_gradient", "expected three arrays of three expressions (vector problem)",
             r.file);
      for (int i = 0; i < 3; ++i) {
        const auto g =
            r.expressions((*v)[std::size_t(i)], pre + "/exact_gradient/" + std::to_string(i), 3);
        l.exact_gradient.insert(l.exact_gradient.end(), g.begin(), g.end());
      }
    }
    // A typo in a derivative would silently change the H1 error: compare with 4th-order
    // differences of `exact` at a few points (skipping points where either is not finite).
    const Eigen::Vector3d probes[] = {
        {0.13, -0.27, 0.31}, {-0.41, 0.22, -0.17}, {0.37, 0.45, -0.29}, {-0.23, -0.36, 0.44}};
    for (int i = 0; i < comps; ++i)
      for (const Eigen::Vector3d& x : probes) {
        const Eigen::Vector3d fd = l.exact[std::size_t(i)].gradient(x);
        for (int d = 0; d < 3; ++d) {
          const double g = l.exact_gradient[std::size_t(3 * i + d)](x);
          if (!std::isfinite(g) || !std::isfinite(fd[d])) continue;
          if (std::abs(g - fd[d]) > 1e-5 * (1 + std::abs(fd[d])))
            fail(pre + "/exact_gradient" + (comps == 1 ? "" : "/" + std::to_string(i)) + "/" +
                     std::to_string(d),
                 "is not the derivative of exact: " + std::to_string(g) + " vs " +
                     std::to_string(fd[d]) + " by finite differences at (" + std::to_string(x.x()) +
                     ", " + std::to_string(x.y()) + ", " + std::to_string(x.z()) + ")",
                 r.file);
        }
      }
  }

  const json* bcs = r.get(o, "boundary_conditions");
  if (bcs) {
    if (!bcs->is_array()) fail(pre + "/boundary_conditions", "expected an array", r.file);
    for (std::size_t i = 0; i < bcs->size(); ++i) {
      const std::string p = pre + "/boundary_conditions/" + std::to_string(i);
      const json& b = (*bcs)[i];
      r.only_keys(b, p, "boundary_conditions[]");
      BoundaryConditionSpec bc;
      const json* type = r.get(b, "type");
      if (!type) fail(p + "/type", "missing (dirichlet, neumann or robin)", r.file);
      bc.type = r.choice_of<BoundaryType>(*type, p + "/type", "boundary_conditions[].type");
      if (bc.type == BoundaryType::robin && comps != 1)
        fail(p + "/type", "robin (convective) conditions are for physics poisson", r.file);
      const json* select = r.get(b, "select");
      if (!select) fail(p + "/select", "missing (e.g. {\"all\": true})", r.file);
      bc.select = read_selection(r, *select, p + "/select");
      if (!c.exterior && mapping::uses_outer_box(bc.select))
        fail(p + "/select", "outer_box needs meshing.exterior: true", r.file);
      if (c.solve_on == SolveOn::both && !mapping::uses_outer_box(bc.select))
        fail(p + "/select",
             "with meshing.solve_on \"both\" the input surface is inside the domain: only the "
             "outer box is boundary (select it with outer_box)",
             r.file);
      if (!c.dense_surface()) {
        const auto k = bc.select.kind;
        if (k != Selection::Kind::all && k != Selection::Kind::tag && k != Selection::Kind::box &&
            k != Selection::Kind::plane)
          fail(p + "/select",
               "normal, and, or, not are evaluated on a dense input surface: they need "
               "meshing.method curved or dense",
               r.file);
      }
      if (bc.type == BoundaryType::robin) {
        // −κ ∂u/∂n = h (u − u_inf): value holds u_inf.
        for (const char* key : {"h", "u_inf"})
          if (!r.get(b, key))
            fail(p + "/" + key,
                 "missing (robin: -kappa du/dn = h (u - u_inf), e.g. \"h\": 10, \"u_inf\": 20)",
                 r.file);
        bc.h = r.expressions(*r.get(b, "h"), p + "/h", 1, /*normal=*/true);
        bc.value = r.expressions(*r.get(b, "u_inf"), p + "/u_inf", 1, /*normal=*/true);
        l.boundary_conditions.push_back(std::move(bc));
        continue;
      }
      const json* value = r.get(b, "value");
      if (!value) fail(p + "/value", "missing", r.file);
      bc.value = r.expressions(*value, p + "/value", comps, /*normal=*/true);
      if (bc.type == BoundaryType::dirichlet)
        for (std::size_t k = 0; k < bc.value.size(); ++k)
          if (bc.value[k].uses_normal())
            fail(p + "/value" + (comps == 1 ? "" : "/" + std::to_string(k)),
                 "nx, ny, nz (the mesh's outward normal at a quadrature point) are for Neumann "
                 "values: a Dirichlet node on an edge has no single normal",
                 r.file);
      if (const json* m = r.get(b, "components")) {
        if (!m->is_array() || m->size() != 3)
          fail(p + "/components", "expected [bool, bool, bool]", r.file);
        for (int k = 0; k < 3; ++k) {
          if (!(*m)[k].is_boolean())
            fail(p + "/components/" + std::to_string(k), "expected true/false", r.file);
          bc.components[k] = (*m)[k].get<bool>();
        }
      }
      l.boundary_conditions.push_back(std::move(bc));
    }
  }

  return l;
}

}  // namespace

CaseSpec read_case(const std::filesystem::path& path, const std::string& output_override) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open case file", {.file = path.string()});
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(std::string("invalid JSON: ") + e.what(), {.file = path.string()});
  }
  return read_case_json(j, path, output_override);
}

CaseSpec read_case_json(const nlohmann::json& given, const std::filesystem::path& path,
                        const std::string& output_override) {
  const Reader r{path.string()};
  r.only_keys(given, "", "");
  CaseSpec c;
  c.case_file = path;
  const auto base = path.parent_path();
  auto resolve = [&](const std::string& p) {
    return std::filesystem::path(p).is_absolute() ? std::filesystem::path(p) : base / p;
  };
  {
    const json* geometry = r.get(given, "geometry");
    if (!geometry) fail("/geometry", "missing (e.g. {\"surface\": \"part.obj\"})", r.file);
    r.only_keys(*geometry, "/geometry", "geometry");
    int sources = 0;
    for (const char* key : {"mesh", "builtin", "surface", "builtin_surface", "mesh_dir"})
      sources += r.get(*geometry, key) != nullptr;
    if (sources != 1)
      fail("/geometry",
           "give exactly one of \"surface\" (a dense triangle surface), \"builtin_surface\", "
           "\"mesh\" (a .msh/.vtu tet mesh), \"builtin\" or \"mesh_dir\" (a curved mesh saved "
           "by curvefem mesh or run)",
           r.file);
  }
  // The case as run (resolved_case.json): the table of case_schema.cpp refuses unknown keys and
  // keys its rules exclude (only for method "curved", only for poisson, ...) and fills in every
  // default; everything below reads the resolved case, whose keys are the given ones or the
  // table's defaults. Paths resolve against the case's folder, numbers given as expressions
  // become their text.
  // Paths become absolute: the parser resolves what it reads again (a no-op then), and
  // resolved_case.json runs from any folder.
  const json j = resolve_case(given, r.file, [&](const CaseKey& k, const json& v) -> json {
    if (k.type == CaseKeyType::path && v.is_string())
      return std::filesystem::absolute(resolve(v.get<std::string>())).string();
    if (k.type == CaseKeyType::expression) return expression_text(v);
    return v;
  });
  const json* geometry = r.get(j, "geometry");
  const json* mesh = r.get(*geometry, "mesh");
  const json* builtin = r.get(*geometry, "builtin");
  const json* surface = r.get(*geometry, "surface");
  const json* builtin_surface = r.get(*geometry, "builtin_surface");
  const json* mesh_dir = r.get(*geometry, "mesh_dir");
  if (mesh_dir) {
    c.mesh_dir = resolve(r.string(*mesh_dir, "/geometry/mesh_dir"));
    for (const char* name : {"mesh.msh", "boundary_map.json"})
      if (!std::filesystem::is_regular_file(c.mesh_dir / name))
        fail("/geometry/mesh_dir",
             "no " + std::string(name) + " in " + c.mesh_dir.string() +
                 " (expected the output directory of curvefem mesh, or of a curved curvefem run)",
             r.file);
  }
  if (mesh) c.mesh = resolve(r.string(*mesh, "/geometry/mesh"));
  if (const json* v = r.get(*geometry, "data_surface")) {
    c.data_surface = resolve(r.string(*v, "/geometry/data_surface"));
    if (!std::filesystem::is_regular_file(c.data_surface))
      fail("/geometry/data_surface", "file not found: " + c.data_surface.string(), r.file);
  }
  if (builtin) {
    r.only_keys(*builtin, "/geometry/builtin", "geometry.builtin");
    const json* shape = r.get(*builtin, "shape");
    if (!shape) fail("/geometry/builtin/shape", "missing (ball or cube)", r.file);
    c.builtin =
        r.choice_of<BuiltinVolume>(*shape, "/geometry/builtin/shape", "geometry.builtin.shape");
    if (const json* v = r.get(*builtin, "size")) {
      c.builtin_size = r.number(*v, "/geometry/builtin/size", "geometry.builtin.size");
    }
    if (const json* v = r.get(*builtin, "divisions")) {
      c.builtin_divisions =
          r.integer(*v, "/geometry/builtin/divisions", "geometry.builtin.divisions");
    }
    if (const json* v = r.get(*builtin, "order"))
      c.builtin_order = r.integer(*v, "/geometry/builtin/order", "geometry.builtin.order");
  }
  if (surface) {
    c.surface = resolve(r.string(*surface, "/geometry/surface"));
    if (!std::filesystem::is_regular_file(c.surface))
      fail("/geometry/surface", "file not found: " + c.surface.string(), r.file);
  }
  if (builtin_surface) {
    const std::string p = "/geometry/builtin_surface";
    const json& b = *builtin_surface;
    r.only_keys(b, p, "geometry.builtin_surface");
    const json* shape = r.get(b, "shape");
    if (!shape) fail(p + "/shape", "missing (sphere, torus or box)", r.file);
    c.builtin_surface =
        r.choice_of<BuiltinSurface>(*shape, p + "/shape", "geometry.builtin_surface.shape");
    const std::string k = "geometry.builtin_surface.";
    if (const json* v = r.get(b, "level"))
      c.sphere_level = r.integer(*v, p + "/level", k + "level");
    if (const json* v = r.get(b, "radius")) c.radius = r.number(*v, p + "/radius", k + "radius");
    if (const json* v = r.get(b, "R")) c.torus_R = r.number(*v, p + "/R");
    if (const json* v = r.get(b, "r")) c.torus_r = r.number(*v, p + "/r");
    if (!(c.torus_r > 0 && c.torus_R > c.torus_r)) fail(p + "/r", "need 0 < r < R", r.file);
    if (const json* v = r.get(b, "nu")) c.torus_nu = r.integer(*v, p + "/nu", k + "nu");
    if (const json* v = r.get(b, "nv")) c.torus_nv = r.integer(*v, p + "/nv", k + "nv");
    if (const json* v = r.get(b, "lo")) c.box_lo = r.point(*v, p + "/lo");
    if (const json* v = r.get(b, "hi")) c.box_hi = r.point(*v, p + "/hi");
    if (!(c.box_lo.array() < c.box_hi.array()).all())
      fail(p + "/hi", "must be above lo in every coordinate", r.file);
    if (const json* v = r.get(b, "divisions"))
      c.box_divisions = r.integer(*v, p + "/divisions", k + "divisions");
  }
  if (const json* f = r.get(*geometry, "features")) {
    const std::string p = "/geometry/features";
    if (f->is_string()) {
      const std::string name = f->get<std::string>();
      const auto& allowed = case_key("geometry.features").allowed;
      if (std::find(allowed.begin(), allowed.end(), name) == allowed.end())
        fail(p,
             "'" + name + "': expected \"auto\", \"none\", {\"angle\": DEG} or " +
                 "{\"file\": \"edges.json\"}",
             r.file);
      c.features = enum_from<FeatureMode>(name);
    } else {
      r.only_keys(*f, p, "geometry.features");
      if (f->size() != 1) fail(p, "give exactly one of angle, file", r.file);
      if (const json* v = r.get(*f, "angle")) {
        c.features = FeatureMode::angle;
        c.feature_angle = r.number(*v, p + "/angle", "geometry.features.angle");
      } else {
        c.features = FeatureMode::file;
        c.feature_file = r.string(*r.get(*f, "file"), p + "/file");
        if (!std::filesystem::is_regular_file(c.feature_file))
          fail(p + "/file", "file not found: " + c.feature_file.string(), r.file);
      }
    }
  }
  const bool dense_input = surface || builtin_surface || mesh_dir;

  if (const json* m = r.get(j, "meshing")) {
    r.only_keys(*m, "/meshing", "meshing");
    if (const json* v = r.get(*m, "method"))
      c.method = r.choice_of<MeshingMethod>(*v, "/meshing/method", "meshing.method");
    if (mesh_dir && c.method != MeshingMethod::curved)
      fail("/meshing/method", "geometry.mesh_dir holds a curved mesh: method \"curved\"", r.file);
    if (c.method == MeshingMethod::given && dense_input)
      fail("/meshing/method",
           "\"given\" takes a tet mesh (geometry.mesh or geometry.builtin), not a surface", r.file);
    if (c.method != MeshingMethod::given && !dense_input)
      fail("/meshing/method",
           "\"" + to_string(c.method) +
               "\" takes a dense surface (geometry.surface or geometry.builtin_surface)",
           r.file);
    if (const json* v = r.get(*m, "order"))
      c.order = r.integer(*v, "/meshing/order", "meshing.order");
    if (const json* v = r.get(*m, "eps")) {
      if (v->is_array()) {
        // ε levels: meshed from one coarsening, solved coarse to fine (run_case.hpp).
        if (v->size() < 2)
          fail("/meshing/eps", "a list of at least two bounds (or one number)", r.file);
        for (std::size_t i = 0; i < v->size(); ++i) {
          const std::string at = "/meshing/eps/" + std::to_string(i);
          const double e = r.number((*v)[i], at, "meshing.eps");
          if (std::find(c.eps_levels.begin(), c.eps_levels.end(), e) != c.eps_levels.end())
            fail(at, "repeats an earlier bound", r.file);
          c.eps_levels.push_back(e);
        }
        std::sort(c.eps_levels.begin(), c.eps_levels.end(), std::greater<>());
        c.eps = c.eps_levels.back();
      } else {
        c.eps = r.number(*v, "/meshing/eps", "meshing.eps");
      }
    }
    if (const json* v = r.get(*m, "eps_field")) {
      c.eps_field = r.string(*v, "/meshing/eps_field");
      if (c.eps_field.empty()) fail("/meshing/eps_field", "an empty expression", r.file);
      (void)Expression(c.eps_field, "/meshing/eps_field");  // syntax errors name the key
    }
    if (const json* v = r.get(*m, "eps_by_tag")) {
      if (!v->is_object() || v->empty())
        fail("/meshing/eps_by_tag",
             "an object of face tags (value or name) and bounds, e.g. {\"3\": 0.002}", r.file);
      for (const auto& [key, value] : v->items()) {
        const std::string at = "/meshing/eps_by_tag/" + key;
        c.eps_by_tag[key] = r.number(value, at, "meshing.eps_by_tag");
      }
    }
    if (const json* v = r.get(*m, "thickness")) {
      c.thickness = r.number(*v, "/meshing/thickness", "meshing.thickness");
    }
    if (const json* v = r.get(*m, "thickness_per_edge")) {
      c.thickness_per_edge =
          r.number(*v, "/meshing/thickness_per_edge", "meshing.thickness_per_edge");
    }
    if (const json* v = r.get(*m, "merge_short_edges")) {
      c.merge_short_edges = r.number(*v, "/meshing/merge_short_edges", "meshing.merge_short_edges");
    }
    if (const json* v = r.get(*m, "eps_samples")) {
      c.eps_samples = r.integer(*v, "/meshing/eps_samples", "meshing.eps_samples");
      if (c.eps_samples == 1)
        fail("/meshing/eps_samples", "must be 0 (vertices only) or a lattice degree >= 2", r.file);
    }
    if (const json* v = r.get(*m, "feature_chains")) {
      if (!v->is_boolean()) fail("/meshing/feature_chains", "expected true/false", r.file);
      c.feature_chains = v->get<bool>();
    }
    if (const json* v = r.get(*m, "curved_coarsening")) {
      if (!v->is_boolean()) fail("/meshing/curved_coarsening", "expected true/false", r.file);
      c.curved_coarsening = v->get<bool>();
    }
    if (const json* v = r.get(*m, "validate")) {
      if (!v->is_boolean()) fail("/meshing/validate", "expected true/false", r.file);
      c.validate = v->get<bool>();
    }
    if (const json* v = r.get(*m, "deterministic")) {
      if (!v->is_boolean()) fail("/meshing/deterministic", "expected true/false", r.file);
      c.deterministic = v->get<bool>();
    }
    if (const json* v = r.get(*m, "exterior")) {
      if (!v->is_boolean()) fail("/meshing/exterior", "expected true/false", r.file);
      c.exterior = v->get<bool>();
    }
    if (const json* v = r.get(*m, "solve_on")) {
      c.solve_on = r.choice_of<SolveOn>(*v, "/meshing/solve_on", "meshing.solve_on");
    }
    if (const json* v = r.get(*m, "padding")) {
      c.padding = r.number(*v, "/meshing/padding", "meshing.padding");
    }
  }

  if (const json* p = r.get(j, "physics")) {
    r.only_keys(*p, "/physics", "physics");
    if (const json* v = r.get(*p, "type"))
      c.physics = r.choice_of<Physics>(*v, "/physics/type", "physics.type");
    if (const json* v = r.get(*p, "kappa")) c.kappa = r.expression(*v, "/physics/kappa");
    if (const json* v = r.get(*p, "kappa_inside"))
      c.kappa_inside = r.expression(*v, "/physics/kappa_inside");
    if (const json* v = r.get(*p, "E")) c.E = r.number(*v, "/physics/E", "physics.E");
    if (const json* v = r.get(*p, "nu")) c.nu = r.number(*v, "/physics/nu", "physics.nu");
    for (const char* key : {"E_inside", "nu_inside"}) {
      const json* v = r.get(*p, key);
      if (!v) continue;
      const std::string path = std::string("/physics/") + key;
      (key[0] == 'E' ? c.E_inside : c.nu_inside) =
          r.number(*v, path, std::string("physics.") + key);
    }
    if (const json* v = r.get(*p, "load_steps"))
      c.load_steps = r.integer(*v, "/physics/load_steps", "physics.load_steps");
  }

  if (const json* d = r.get(j, "discretization")) {
    r.only_keys(*d, "/discretization", "discretization");
    if (const json* v = r.get(*d, "target_error")) {
      c.target_error = r.number(*v, "/discretization/target_error", "discretization.target_error");
    }
    if (const json* v = r.get(*d, "boundary_values_at")) {
      c.boundary_values_at = r.choice_of<BoundaryValuesAt>(*v, "/discretization/boundary_values_at",
                                                           "discretization.boundary_values_at");
      if (c.boundary_values_at == BoundaryValuesAt::shifted && c.physics == Physics::neo_hookean)
        fail("/discretization/boundary_values_at",
             "\"shifted\" is for the linear problems (poisson, linear_elasticity)", r.file);
    }
    if (const json* v = r.get(*d, "geometry")) {
      c.geometry =
          r.choice_of<SolveGeometry>(*v, "/discretization/geometry", "discretization.geometry");
    }
    if (const json* v = r.get(*d, "partial_dirichlet")) {
      c.partial_dirichlet = r.choice_of<PartialDirichlet>(*v, "/discretization/partial_dirichlet",
                                                          "discretization.partial_dirichlet");
      if (c.partial_dirichlet == PartialDirichlet::nitsche && c.physics == Physics::neo_hookean)
        fail("/discretization/partial_dirichlet",
             "Neo-Hookean imposes Dirichlet data nodally only (\"nodal\")", r.file);
    }
    if (const json* v = r.get(*d, "degree"))
      c.degree = r.integer(*v, "/discretization/degree", "discretization.degree");
    if (const json* v = r.get(*d, "quadrature")) {
      // "default" is what resolved_case.json writes, so a resolved case runs again unchanged.
      if (!(v->is_string() && v->get<std::string>() == "default"))
        c.quadrature = r.integer(*v, "/discretization/quadrature", "discretization.quadrature");
    }
  }
  if (const json* lc = r.get(j, "load_cases")) {
    if (!lc->is_array() || lc->empty())
      fail("/load_cases", "expected a non-empty array of {name, boundary_conditions, ...}", r.file);
    std::set<std::string> names;
    for (std::size_t i = 0; i < lc->size(); ++i) {
      const std::string p = "/load_cases/" + std::to_string(i);
      const json& o = (*lc)[i];
      r.only_keys(o, p, "load_cases[]");
      const json* name = r.get(o, "name");
      if (!name)
        fail(p + "/name", "missing (a name for the load case's fields and report)", r.file);
      LoadCase l = read_load(r, o, p, c);
      l.name = r.string(*name, p + "/name");
      if (l.name.empty() ||
          l.name.find_first_not_of(
              "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
              std::string::npos)
        fail(p + "/name",
             "'" + l.name + "': use letters, digits, _ and - (it names fields and files)", r.file);
      if (!names.insert(l.name).second)
        fail(p + "/name", "'" + l.name + "' names two load cases", r.file);
      c.load_cases.push_back(std::move(l));
    }
  } else {
    LoadCase l = read_load(r, j, "", c);
    c.rhs = std::move(l.rhs);
    c.exact = std::move(l.exact);
    c.exact_gradient = std::move(l.exact_gradient);
    c.boundary_conditions = std::move(l.boundary_conditions);
  }

  if (const json* s = r.get(j, "solver")) {
    r.only_keys(*s, "/solver", "solver");
    if (const json* v = r.get(*s, "type"))
      c.solver = r.choice_of<SolverType>(*v, "/solver/type", "solver.type");
    if (const json* v = r.get(*s, "rtol"))
      c.solver_rtol = r.number(*v, "/solver/rtol", "solver.rtol");
    if (const json* v = r.get(*s, "max_iterations"))
      c.solver_max_iterations = r.integer(*v, "/solver/max_iterations", "solver.max_iterations");
    if (const json* v = r.get(*s, "near_nullspace")) {
      if (!v->is_boolean()) fail("/solver/near_nullspace", "expected true/false", r.file);
      c.solver_near_nullspace = v->get<bool>();
    }
    if (const json* v = r.get(*s, "preconditioner")) {
      c.solver_preconditioner =
          r.choice_of<Preconditioner>(*v, "/solver/preconditioner", "solver.preconditioner");
    }
    if (const json* v = r.get(*s, "parallel_ptap"))
      c.solver_parallel_ptap =
          r.choice_of<ParallelPtap>(*v, "/solver/parallel_ptap", "solver.parallel_ptap");
    if (const json* v = r.get(*s, "rank_balance"))
      c.solver_rank_balance =
          r.choice_of<RankBalance>(*v, "/solver/rank_balance", "solver.rank_balance");
  }
  std::string out = "out";
  if (const json* o = r.get(j, "output")) {
    r.only_keys(*o, "/output", "output");
    if (const json* v = r.get(*o, "dir")) out = r.string(*v, "/output/dir");
    if (const json* v = r.get(*o, "surface_values"))
      c.surface_values =
          r.choice_of<SurfaceValues>(*v, "/output/surface_values", "output.surface_values");
  }
  c.output_dir = output_override.empty() ? resolve(out) : std::filesystem::path(output_override);

  // The resolved case as run: the output folder (-o replaces output.dir), ε levels in the order
  // they are solved (coarse to fine) and the selections in their read form (a normal selection's
  // angle filled in).
  json res = j;
  res["output"]["dir"] = c.output_dir.string();
  if (!c.eps_levels.empty()) res["meshing"]["eps"] = c.eps_levels;
  auto selections = [&](json& bcs, const std::vector<BoundaryConditionSpec>& specs) {
    for (std::size_t i = 0; i < specs.size(); ++i)
      bcs.at(i)["select"] = selection_json(specs[i].select);
  };
  if (c.load_cases.empty())
    selections(res["boundary_conditions"], c.boundary_conditions);
  else
    for (std::size_t i = 0; i < c.load_cases.size(); ++i)
      selections(res["load_cases"][i]["boundary_conditions"], c.load_cases[i].boundary_conditions);
  c.resolved = res;
  return c;
}

}  // namespace curvefem::pipeline
