// The closed sets of values of case keys (the `allowed` lists of case_schema.cpp) as enums, with
// their JSON spelling. CaseSpec holds these; the strings exist only in case files, reports and
// messages. `to_string(e)` gives the spelling, `enum_from<E>(text)` the value (throws
// curvefem::Error for a spelling the enum does not have: the parser checks against the schema
// first, so that is a bug, not bad input).
#pragma once

#include <cstddef>
#include <iterator>
#include <string>
#include <string_view>

#include "meshing/core/error.hpp"

namespace curvefem::pipeline {

enum class BuiltinVolume { none, ball, cube };                   ///< geometry.builtin.shape
enum class BuiltinSurface { none, sphere, torus, box };          ///< geometry.builtin_surface.shape
enum class FeatureMode { automatic, none, angle, file };         ///< geometry.features
enum class MeshingMethod { given, curved, dense };               ///< meshing.method
enum class SolveOn { outside, both };                            ///< meshing.solve_on
enum class Physics { poisson, linear_elasticity, neo_hookean };  ///< physics.type
enum class PartialDirichlet { nitsche, nodal };              ///< discretization.partial_dirichlet
enum class SolveGeometry { iso, mesh };                      ///< discretization.geometry
enum class SolverType { automatic, direct, cg };             ///< solver.type
enum class Preconditioner { gamg, hypre, ml };               ///< solver.preconditioner
enum class ParallelPtap { automatic, allatonce, scalable };  ///< solver.parallel_ptap
enum class RankBalance { memory, rows };                     ///< solver.rank_balance
enum class BoundaryType { dirichlet, neumann, robin };       ///< boundary_conditions[].type
enum class SurfaceValues { extended, image };                ///< output.surface_values
enum class BoundaryValuesAt { input, mesh, shifted };        ///< discretization.boundary_values_at

/// The spelling of every value, in the enum's order ("" for a value no file spells: none).
template <class E>
struct EnumNames;
template <class E>
std::string to_string(E e) requires requires {
  EnumNames<E>::names;
}
{ return std::string(EnumNames<E>::names[std::size_t(e)]); }

template <class E>
E enum_from(std::string_view text) {
  const auto& names = EnumNames<E>::names;
  for (std::size_t i = 0; i < std::size(names); ++i)
    if (names[i] == text) return E(i);
  throw Error("no value '" + std::string(text) + "' in this enum (pipeline/case_enums.hpp)");
}

// Also JSON conversion by spelling (as NLOHMANN_JSON_SERIALIZE_ENUM does): without it
// nlohmann::json would write an enum as its number.
#define CURVEFEM_ENUM_NAMES(E, ...)                            \
  template <>                                                  \
  struct EnumNames<E> {                                        \
    static constexpr std::string_view names[] = {__VA_ARGS__}; \
  };                                                           \
  template <class BasicJsonType>                               \
  void to_json(BasicJsonType& j, const E& e) {                 \
    j = std::string(EnumNames<E>::names[std::size_t(e)]);      \
  }                                                            \
  template <class BasicJsonType>                               \
  void from_json(const BasicJsonType& j, E& e) {               \
    e = enum_from<E>(j.template get<std::string>());           \
  }
CURVEFEM_ENUM_NAMES(BuiltinVolume, "", "ball", "cube")
CURVEFEM_ENUM_NAMES(BuiltinSurface, "", "sphere", "torus", "box")
CURVEFEM_ENUM_NAMES(FeatureMode, "auto", "none", "angle", "file")
CURVEFEM_ENUM_NAMES(MeshingMethod, "given", "curved", "dense")
CURVEFEM_ENUM_NAMES(SolveOn, "outside", "both")
CURVEFEM_ENUM_NAMES(Physics, "poisson", "linear_elasticity", "neo_hookean")
CURVEFEM_ENUM_NAMES(PartialDirichlet, "nitsche", "nodal")
CURVEFEM_ENUM_NAMES(SolveGeometry, "iso", "mesh")
CURVEFEM_ENUM_NAMES(SolverType, "auto", "direct", "cg")
CURVEFEM_ENUM_NAMES(Preconditioner, "gamg", "hypre", "ml")
CURVEFEM_ENUM_NAMES(ParallelPtap, "auto", "allatonce", "scalable")
CURVEFEM_ENUM_NAMES(RankBalance, "memory", "rows")
CURVEFEM_ENUM_NAMES(BoundaryType, "dirichlet", "neumann", "robin")
CURVEFEM_ENUM_NAMES(SurfaceValues, "extended", "image")
CURVEFEM_ENUM_NAMES(BoundaryValuesAt, "input", "mesh", "shifted")
#undef CURVEFEM_ENUM_NAMES

}  // namespace curvefem::pipeline
