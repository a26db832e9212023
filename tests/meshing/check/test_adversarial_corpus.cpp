// The adversarial corpus (meshing/core/adversarial.hpp) is made of valid meshing inputs: every
// surface is closed, manifold, outward, free of self-intersections and accepted by check_surface,
// and the stress each one names is really there (singular vertices, slivers, thinness).
#include <gtest/gtest.h>

#include <set>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/shell/extrusion_direction.hpp"

using namespace curvefem;

TEST(AdversarialCorpus, EverySurfaceIsAValidInput) {
  const auto& list = adversarial_surfaces();
  EXPECT_GE(list.size(), 30u);
  std::set<std::string> names;
  for (const auto& s : list) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    if (s.name == "noise_sphere_big") continue;  // 327,680 faces: the benchmark's
    const SurfaceMesh m = make_adversarial(s.name);
    const check::CheckReport r = check::check_surface(m);
    EXPECT_TRUE(r.acceptable) << s.name << ": "
                              << (r.defects.empty() ? "" : r.defects.front().message);
    EXPECT_EQ(r.self_intersecting_pairs, 0) << s.name;
    EXPECT_GT(r.signed_volume, 0) << s.name;
  }
  EXPECT_THROW(make_adversarial("no_such_surface"), InputError);
}

TEST(AdversarialCorpus, TheStressesAreThere) {
  namespace sh = curvefem::meshing::shell;
  auto singular = [](const std::string& name) {
    const SurfaceMesh m = make_adversarial(name);
    return sh::extrusion_directions(m.V, m.F).singular_count;
  };
  EXPECT_EQ(singular("knife_disc"), 64);  // the rim
  EXPECT_EQ(singular("knife_disc_slivers"), 64);
  EXPECT_EQ(singular("needle_sphere_8"), 8);  // the tips
  EXPECT_EQ(singular("needle_sphere_32"), 32);
  EXPECT_EQ(singular("sphere_coarse"), 0);
  EXPECT_GT(singular("noise_sphere_20"), 0);  // folds of the radial noise
  const check::CheckReport slivers = check::check_surface(make_adversarial("sliver_sphere_0001"));
  EXPECT_LT(slivers.min_angle_deg, 1e-3);
  EXPECT_EQ(slivers.degenerate_faces, 0);
}
