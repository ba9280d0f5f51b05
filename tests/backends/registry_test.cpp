#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "backends/registry.h"
#include "base/error.h"
#include "tests/support/error_of.h"
#include "tests/support/scenes.h"

namespace rp {
namespace {

/// True when make_backend accepts a scene passed as S (a requires-expression needs a template
/// to turn an ill-formed call into false).
template <typename S>
constexpr bool builds_over = requires(S&& s) { make_backend("simd", std::forward<S>(s)); };

// A backend keeps a reference to its scene, so a temporary scene, which dies at the end of the
// call, must not compile; a scene the caller keeps, or one the backend shares, must.
static_assert(!builds_over<Scene>);
static_assert(!builds_over<const Scene>);
static_assert(builds_over<Scene&>);
static_assert(builds_over<const Scene&>);
static_assert(builds_over<std::shared_ptr<const Scene>>);
static_assert(builds_over<std::shared_ptr<Scene>>);

TEST(Registry, ASharedSceneLivesAsLongAsTheBackend) {
  for (const std::string& name : available_backends()) {
    auto scene = std::make_shared<Scene>(test::tessellated_sphere(24, 12));
    const std::weak_ptr<const Scene> watch = scene;
    std::unique_ptr<Backend> backend = make_backend(name, std::shared_ptr<const Scene>(std::move(scene)));
    ASSERT_FALSE(watch.expired()) << name;  // the caller let go; the backend still holds the scene

    // Traced after the caller's pointer is gone: the sphere of radius 1 seen from z = 5.
    std::vector<Ray> rays(2);
    rays[0].org = {0, 0, 5};
    rays[1].org = {0, 3, 5};
    for (Ray& r : rays) r.dir = {0, 0, -1};
    std::vector<Hit> hits(rays.size());
    backend->intersect(rays, hits, Coherence::incoherent);
    EXPECT_TRUE(hits[0].hit()) << name;
    EXPECT_NEAR(hits[0].t, 4.0f, 0.05f) << name;
    EXPECT_FALSE(hits[1].hit()) << name;
    std::vector<uint8_t> occluded(rays.size());
    backend->occluded(rays, occluded, Coherence::coherent);
    EXPECT_EQ(occluded, (std::vector<uint8_t>{1, 0})) << name;
    EXPECT_EQ(backend->info().name, name);

    backend.reset();
    EXPECT_TRUE(watch.expired()) << name;  // the last owner was the backend
  }
}

TEST(Registry, EveryMethodIsNamedOnceAsBackendVariantColonMethod) {
  std::vector<std::string> names;
  for (const TraceMethod& m : list_methods()) {
    const std::string suffix =
        m.coherence == Coherence::incoherent && m.name.ends_with("-incoherent") ? "-incoherent" : "";
    EXPECT_EQ(m.name, m.backend + "/" + m.variant + ":" + m.method + suffix);
    EXPECT_EQ(std::ranges::count(names, m.name), 0) << m.name << " twice";
    names.push_back(m.name);
  }
  // Every variant with every method of each available backend, nothing else.
  size_t expected = 0;
  for (const BackendEntry& e : list_backends())
    if (e.available) expected += e.variants.size() * (e.coherent_methods.size() + e.incoherent_methods.size());
  EXPECT_EQ(names.size(), expected);
  // Embree's stream is both a coherent and an incoherent method: the incoherent one says so.
  EXPECT_EQ(std::ranges::count(names, "embree/default:stream"), 1);
  EXPECT_EQ(std::ranges::count(names, "embree/default:stream-incoherent"), 1);
  EXPECT_EQ(std::ranges::count(names, "embree/robust:single"), 1);
}

TEST(Registry, ASharedSceneMustNotBeNull) {
  EXPECT_EQ(test::error_of([] { make_backend("embree", std::shared_ptr<const Scene>()); }),
            "make_backend: no scene (a null shared_ptr)");
}

TEST(Registry, ASharedSceneIsCheckedAsAnyOther) {
  const auto scene = std::make_shared<const Scene>();
  EXPECT_EQ(test::error_of([&] { make_backend("nope", scene); }), "unknown backend 'nope' (available: embree, simd)");
  EXPECT_EQ(test::error_of([&] {
              make_backend("embree", scene,
                           {.variant = "fastest", .device_config = {}, .coherent_method = {}, .incoherent_method = {}});
            }),
            "'fastest' is not a variant of embree (default, robust, compact, high, dynamic)");
}

}  // namespace
}  // namespace rp
