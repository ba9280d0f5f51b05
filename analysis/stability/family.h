#pragma once
/// The ray families of `raypack stability` (analysis/stability.h), for the files that
/// build and judge them: what a family holds, where its generators read geometry, and the one
/// table of every family (families.cpp). Internal to analysis.

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "analysis/reference.h"
#include "core/scene.h"

namespace rp::stability {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// A scene and its seeded rays. fan_begin/fan: the primitives ray i is aimed at (may be
/// empty), which the scalar methods test; source[i]: the primitive ray i leaves (leaving
/// families only).
struct Family {
  std::string name, param;
  int exponent = 0;
  bool has_exponent = false;
  std::shared_ptr<const Scene> scene;
  std::vector<Ray> rays;
  std::vector<uint32_t> fan_begin{0}, fan;
  std::vector<uint32_t> source;
  std::vector<uint8_t> judged;  ///< 0: no right answer (a ray inside a triangle's plane): NaN and interval checks only
  bool invalid = false;         ///< every ray has a NaN or Inf in it
  double diagonal = 1.0;        ///< of the scene's bounds (self-hits on curved surfaces are judged against it)

  void add(const Ray& r, std::span<const uint32_t> prims = {}, bool judge = true) {
    rays.push_back(r);
    judged.push_back(judge);
    fan.insert(fan.end(), prims.begin(), prims.end());
    fan_begin.push_back(uint32_t(fan.size()));
  }
  std::span<const uint32_t> fan_of(size_t i) const { return {fan.data() + fan_begin[i], fan.data() + fan_begin[i + 1]}; }
};

/// Where the generators read geometry: the float vertices of `base`, in double, mapped by
/// p * scale + offset. For a moved or scaled copy of a scene the rays are aimed at where its
/// edges, vertices and surfaces ideally are (the copy's triangles share the base's prim ids),
/// not at its rounded vertices, which far from the origin collapse into a lattice.
struct Geom {
  const Scene* base = nullptr;
  double scale = 1.0;
  Vec3d offset{0.0};

  Vec3d map(const Vec3f& p) const { return Vec3d(p) * scale + offset; }
  Vec3d vertex(size_t mesh, uint32_t i) const { return map(base->meshes()[mesh].positions[i]); }
  Vec3d corner(uint32_t tri, int c) const {
    const auto ref = base->locate(tri);
    return map(base->meshes()[ref.shape].vertex(ref.local, c));
  }
  /// Unit normal of triangle `tri`, (0,0,0) when degenerate.
  Vec3d normal(uint32_t tri) const {
    const Vec3d a = corner(tri, 0), n = cross(corner(tri, 1) - a, corner(tri, 2) - a);
    const double l = length(n);
    return l > 0 ? n / l : Vec3d(0.0);
  }
  /// A uniformly random point of triangle `tri` with every barycentric >= 0.05 (away from the
  /// edges, whose rays the edge and vertex families aim at on purpose).
  Vec3d point(uint32_t tri, std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double x = u(rng), y = u(rng);
    if (x + y > 1.0) {
      x = 1.0 - x;
      y = 1.0 - y;
    }
    const double b1 = 0.05 + 0.85 * x, b2 = 0.05 + 0.85 * y;
    return corner(tri, 0) * (1 - b1 - b2) + corner(tri, 1) * b1 + corner(tri, 2) * b2;
  }
  double diagonal() const {
    const Box3f b = base->bounds();
    return b.empty() ? scale : std::max(1e-30, length(Vec3d(b.extent())) * scale);
  }
};

/// Triangle adjacency of every mesh by vertex index: manifold edges (exactly two triangles)
/// and the triangle fan of every vertex shared by three or more. Triangle ids are prim ids.
struct Topology {
  struct Edge {
    uint32_t mesh, a, b;
    std::array<uint32_t, 2> tris;
  };
  struct Vertex {
    uint32_t mesh, index;
  };
  std::vector<Edge> edges;
  std::vector<Vertex> vertices;
  std::vector<uint32_t> fan_begin{0}, fan;  ///< CSR: the triangles around vertices[i]

  explicit Topology(const Scene& s);
  std::span<const uint32_t> vertex_fan(size_t v) const { return {fan.data() + fan_begin[v], fan.data() + fan_begin[v + 1]}; }
};

/// What a family's generator reads: the geometry its rays aim at (the given scene, or where a
/// moved copy's geometry ideally is), the given scene's adjacency, and the reference of the
/// scene the rays are traced in.
struct Context {
  const Geom& geom;
  const Topology& topology;
  const Reference& reference;
};

/// Which scene a family's rays are traced in.
enum class Where : uint8_t {
  given,       ///< the scene `raypack stability` was given (its meshes)
  own,         ///< a scene the family builds (FamilySpec::scene)
  translated,  ///< the given scene moved by 10^k, k = 0..7
  scaled,      ///< the given scene scaled by 10^k, k = -6, -3, 3, 6
  moved,       ///< every translated and every scaled copy
};

/// One family: adding a family is one entry of family_table().
struct FamilySpec {
  const char* name;
  const char* description;
  Where where;
  /// Its random stream is seeded by this key (nullptr: the name) followed by the family's
  /// parameter (the copy's 1e<k>), so families that share a key share their rays.
  const char* seed_key;
  std::shared_ptr<Scene> (*scene)(std::mt19937_64& rng);  ///< Where::own: builds the scene
  void (*generate)(Family& f, const Context& c, uint32_t n, std::mt19937_64& rng);
};

/// Every family, in the order run() reports them within a scene.
const std::vector<FamilySpec>& family_table();

/// The length of the diagonal of `s`'s bounds (1 when empty).
double scene_diagonal(const Scene& s);

}  // namespace rp::stability
