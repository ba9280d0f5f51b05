#include "engine/analysis/stability.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <span>

#include "engine/error.h"
#include "engine/geometry/quadric.h"
#include "engine/geometry/sphere.h"
#include "engine/geometry/triangle.h"
#include "engine/offset.h"
#include "engine/analysis/reference.h"

namespace rp::stability {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

const std::vector<std::pair<std::string, std::string>> kFamilies = {
    {"edges", "rays aimed exactly at midpoints of shared mesh edges, from outside and inside"},
    {"vertices", "rays aimed exactly at shared mesh vertices, from outside and inside"},
    {"grazing", "rays at 1e-1..1e-6 rad to a triangle's plane, aimed inside it"},
    {"axis_parallel", "rays along +-x/y/z with +-0 components through mesh vertices, origins on the bounding box faces"},
    {"flat_boxes", "axis-aligned flat squares (zero-thickness boxes), rays across and inside their planes"},
    {"needles", "needle and near-degenerate triangles (aspect 1e2..1e7), rays aimed at their centroids"},
    {"nan_inf", "rays with a NaN or +-Inf in the origin, direction, tnear or tfar"},
    {"far_spheres", "spheres of radius 1 at distance 1e1..1e7, rays from the origin aimed inside their disc"},
    {"tangent", "rays passing sphere and quadric surfaces tangentially, 1e-1..1e-6 (relative) to either side"},
    {"translated", "the scene moved by 10^k, k = 0..7: rays at shared edges, vertices and surface points"},
    {"scaled", "the scene scaled by 10^k, k = -6, -3, 3, 6: the same rays"},
    {"leaving_raw", "rays leaving computed hit points (reflection and transmission side), no offset, at every translation and scale"},
    {"leaving_offset", "the same rays with the origin offset as the renderer does (Waechter and Binder 2019)"},
};

uint64_t fnv1a(const std::string& s, uint64_t seed) {
  uint64_t h = 1469598103934665603ull ^ seed;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

Vec3d dvec(const Vec3f& v) { return Vec3d(v); }

Ray make_ray(const Vec3d& from, const Vec3d& to) {
  Ray r;
  r.org = Vec3f(from);
  r.dir = Vec3f(to - from);
  return r;
}

/// Where the generators read geometry: the float vertices of `base`, in double, mapped by
/// p * scale + offset. For a moved or scaled copy of a scene the rays are aimed at where its
/// edges, vertices and surfaces ideally are (the copy's triangles share the base's prim ids),
/// not at its rounded vertices, which far from the origin collapse into a lattice.
struct Geom {
  const Scene* base = nullptr;
  double scale = 1.0;
  Vec3d offset{0.0};

  Vec3d map(const Vec3f& p) const { return dvec(p) * scale + offset; }
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
    return b.empty() ? scale : std::max(1e-30, length(dvec(b.extent())) * scale);
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

  explicit Topology(const Scene& s) {
    std::vector<std::pair<uint64_t, uint32_t>> keyed;  // (edge key, triangle), sorted: deterministic
    for (uint32_t m = 0; m < s.meshes().size(); ++m) {
      const TriangleMesh& mesh = s.meshes()[m];
      const uint32_t base = s.mesh_base(m);
      std::vector<std::vector<uint32_t>> around(mesh.positions.size());
      keyed.clear();
      for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
        for (int c = 0; c < 3; ++c) {
          const uint32_t i = mesh.indices[3 * t + c], j = mesh.indices[3 * t + (c + 1) % 3];
          keyed.push_back({(uint64_t(std::min(i, j)) << 32) | std::max(i, j), base + t});
          around[i].push_back(base + t);
        }
      for (uint32_t v = 0; v < around.size(); ++v)
        if (around[v].size() >= 3) {
          vertices.push_back({m, v});
          fan.insert(fan.end(), around[v].begin(), around[v].end());
          fan_begin.push_back(uint32_t(fan.size()));
        }
      std::sort(keyed.begin(), keyed.end());
      for (size_t k = 0; k < keyed.size();) {
        size_t e = k;
        while (e < keyed.size() && keyed[e].first == keyed[k].first) ++e;
        if (e - k == 2)
          edges.push_back({m, uint32_t(keyed[k].first >> 32), uint32_t(keyed[k].first),
                           {keyed[k].second, keyed[k + 1].second}});
        k = e;
      }
    }
  }
  std::span<const uint32_t> vertex_fan(size_t v) const { return {fan.data() + fan_begin[v], fan.data() + fan_begin[v + 1]}; }
};

/// A unit direction within 60 degrees of unit `n`.
Vec3d around(const Vec3d& n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double theta = u(rng) * kPi / 3, phi = u(rng) * 2 * kPi;
  const Basis<double> b = orthonormal_basis(n);
  return n * std::cos(theta) + (b.t * std::cos(phi) + b.b * std::sin(phi)) * std::sin(theta);
}

double scene_diagonal(const Scene& s) {
  const Box3f b = s.bounds();
  return b.empty() ? 1.0 : std::max(1e-30, length(dvec(b.extent())));
}

/// Rays at a point p with unit normal n: from outside (along n) or inside (against it).
void add_approach(Family& f, const Vec3d& p, const Vec3d& n, double diag, std::mt19937_64& rng,
                  std::span<const uint32_t> fan) {
  std::uniform_real_distribution<double> u(0.05, 0.5);
  const bool inside = rng() & 1;
  const Vec3d d = around(n, rng) * (inside ? -1.0 : 1.0);
  f.add(make_ray(p + d * (diag * u(rng)), p), fan);
}

void gen_edges(Family& f, const Geom& g, const Topology& topo, uint32_t n, std::mt19937_64& rng) {
  if (topo.edges.empty()) return;
  const double diag = g.diagonal();
  for (uint32_t i = 0; i < n; ++i) {
    const Topology::Edge& e = topo.edges[rng() % topo.edges.size()];
    Vec3d nn = g.normal(e.tris[0]) + g.normal(e.tris[1]);
    if (length(nn) == 0.0) nn = g.normal(e.tris[0]);
    if (length(nn) == 0.0) continue;
    add_approach(f, (g.vertex(e.mesh, e.a) + g.vertex(e.mesh, e.b)) * 0.5, normalize(nn), diag, rng, e.tris);
  }
}

void gen_vertices(Family& f, const Geom& g, const Topology& topo, uint32_t n, std::mt19937_64& rng) {
  if (topo.vertices.empty()) return;
  const double diag = g.diagonal();
  for (uint32_t i = 0; i < n; ++i) {
    const size_t v = rng() % topo.vertices.size();
    Vec3d nn(0.0);
    for (uint32_t t : topo.vertex_fan(v)) nn = nn + g.normal(t);
    if (length(nn) == 0.0) continue;
    add_approach(f, g.vertex(topo.vertices[v].mesh, topo.vertices[v].index), normalize(nn), diag, rng,
                 topo.vertex_fan(v));
  }
}

void gen_surface(Family& f, const Geom& g, uint32_t n, std::mt19937_64& rng) {
  const uint32_t tris = g.base->triangle_count();
  if (tris == 0) return;
  const double diag = g.diagonal();
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t t = uint32_t(rng() % tris);
    const Vec3d nn = g.normal(t);
    if (length(nn) == 0.0) continue;
    add_approach(f, g.point(t, rng), nn, diag, rng, {});
  }
}

void gen_grazing(Family& f, const Geom& g, uint32_t n, std::mt19937_64& rng) {
  const uint32_t tris = g.base->triangle_count();
  if (tris == 0) return;
  const double diag = g.diagonal();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t t = uint32_t(rng() % tris);
    const Vec3d nn = g.normal(t);
    if (length(nn) == 0.0) continue;
    const Basis<double> b = orthonormal_basis(nn);
    const double phi = u(rng) * 2 * kPi, angle = std::pow(10.0, -1.0 - 5.0 * u(rng));
    const Vec3d d = (b.t * std::cos(phi) + b.b * std::sin(phi)) * std::cos(angle) + nn * std::sin(angle);
    const Vec3d p = g.point(t, rng);
    const uint32_t fan[1] = {t};
    f.add(make_ray(p - d * (diag * (0.05 + 0.45 * u(rng))), p), fan);
  }
}

void gen_axis_parallel(Family& f, const Geom& g, const Topology& topo, uint32_t n, std::mt19937_64& rng) {
  if (topo.vertices.empty()) return;
  const Box3f box = f.scene->bounds();
  for (uint32_t i = 0; i < n; ++i) {
    const size_t v = rng() % topo.vertices.size();
    const int axis = int(rng() % 3);
    const bool neg = rng() & 1;
    Ray r;
    r.org = Vec3f(g.vertex(topo.vertices[v].mesh, topo.vertices[v].index));
    r.org[axis] = neg ? box.hi[axis] : box.lo[axis];  // on the face of the scene's box
    r.dir = Vec3f((rng() & 1) ? -0.0f : 0.0f, (rng() & 1) ? -0.0f : 0.0f, (rng() & 1) ? -0.0f : 0.0f);
    r.dir[axis] = neg ? -1.0f : 1.0f;
    f.add(r, topo.vertex_fan(v));
  }
}

std::shared_ptr<Scene> flat_boxes_scene() {
  auto s = std::make_shared<Scene>();
  TriangleMesh m;
  m.name = "flat_squares";
  for (int axis = 0; axis < 3; ++axis)
    for (int k = -2; k <= 2; ++k) {
      const uint32_t base = uint32_t(m.positions.size());
      for (int c = 0; c < 4; ++c) {
        Vec3f p;
        p[axis] = float(k) * 0.5f;
        p[(axis + 1) % 3] = (c == 1 || c == 2) ? 1.0f : -1.0f;
        p[(axis + 2) % 3] = (c >= 2) ? 1.0f : -1.0f;
        p[(axis + 1) % 3] += float(k) * 3.0f;  // squares apart from each other
        m.positions.push_back(p);
      }
      for (uint32_t idx : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + idx);
    }
  s->add_mesh(std::move(m));
  return s;
}

void gen_flat_boxes(Family& f, uint32_t n, std::mt19937_64& rng) {
  const Scene& s = *f.scene;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t t = uint32_t(rng() % s.triangle_count());
    const Geom g{&s};
    const Vec3d p = g.point(t, rng), nn = g.normal(t);
    const uint32_t fan[1] = {t};
    if (i % 3 == 0) {  // in the square's plane: the box has zero thickness along the ray's normal axis
      const Basis<double> b = orthonormal_basis(nn);
      const double phi = u(rng) * kPi;
      Ray r = make_ray(p - (b.t * std::cos(phi) + b.b * std::sin(phi)) * 4.0, p);
      for (int a = 0; a < 3; ++a)
        if (nn[a] != 0.0) r.dir[a] = (rng() & 1) ? -0.0f : 0.0f;
      f.add(r, fan, false);  // in the plane: hit and miss are both right
    } else {
      add_approach(f, p, nn, 8.0, rng, fan);
    }
  }
}

std::shared_ptr<Scene> needles_scene(std::mt19937_64& rng) {
  auto s = std::make_shared<Scene>();
  TriangleMesh m;
  m.name = "needles";
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 2; k <= 7; ++k)
    for (int j = 0; j < 8; ++j) {
      const Vec3d c{3.0 * (k - 4.5), 3.0 * (j - 3.5), 0.0};
      Vec3d axis = normalize(Vec3d{u(rng), u(rng), u(rng)});
      Vec3d side = normalize(cross(axis, Vec3d{u(rng), u(rng), u(rng)}));
      const double w = std::pow(10.0, -k);
      const uint32_t base = uint32_t(m.positions.size());
      m.positions.push_back(Vec3f(c - axis));
      m.positions.push_back(Vec3f(c + axis));
      // odd j: the apex almost on the long edge (near-degenerate), else a thin needle
      m.positions.push_back(Vec3f(c + axis * (j % 2 ? 0.999 : 0.0) + side * w));
      for (uint32_t idx : {0u, 1u, 2u}) m.indices.push_back(base + idx);
    }
  s->add_mesh(std::move(m));
  return s;
}

void gen_needles(Family& f, uint32_t n, std::mt19937_64& rng) {
  const Scene& s = *f.scene;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t t = uint32_t(rng() % s.triangle_count());
    const auto ref = s.locate(t);
    const TriangleMesh& m = s.meshes()[ref.shape];
    const Vec3d a = dvec(m.vertex(ref.local, 0)), b = dvec(m.vertex(ref.local, 1)), c = dvec(m.vertex(ref.local, 2));
    Vec3d nn = Geom{&s}.normal(t);
    if (length(nn) == 0.0) nn = Vec3d{0.0, 0.0, 1.0};  // collapsed in float: the reference decides
    const uint32_t fan[1] = {t};
    add_approach(f, (a + b + c) / 3.0, nn, 6.0, rng, fan);
  }
}

void gen_nan_inf(Family& f, const Geom& g, uint32_t n, std::mt19937_64& rng) {
  Family valid;
  valid.scene = f.scene;
  gen_surface(valid, g, n, rng);
  const float bad[3] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                        -std::numeric_limits<float>::infinity()};
  for (size_t i = 0; i < valid.rays.size(); ++i) {
    Ray r = valid.rays[i];
    const float x = bad[rng() % 3];
    switch (rng() % 8) {
      case 0: r.org.x = x; break;
      case 1: r.org.y = x; break;
      case 2: r.org.z = x; break;
      case 3: r.dir.x = x; break;
      case 4: r.dir.y = x; break;
      case 5: r.dir.z = x; break;
      case 6: r.tnear = x; break;
      default: r.tfar = x == std::numeric_limits<float>::infinity() ? std::numeric_limits<float>::quiet_NaN() : x;
    }
    f.add(r);
  }
  f.invalid = true;
}

std::shared_ptr<Scene> far_spheres_scene(std::mt19937_64& rng) {
  auto s = std::make_shared<Scene>();
  std::normal_distribution<double> g(0.0, 1.0);
  for (int k = 1; k <= 7; ++k) {
    const Vec3d d = normalize(Vec3d{g(rng), g(rng), g(rng)});
    s->add_sphere({Vec3f(d * std::pow(10.0, k)), 1.0f, 0});
  }
  return s;
}

void gen_far_spheres(Family& f, uint32_t n, std::mt19937_64& rng) {
  const Scene& s = *f.scene;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t k = uint32_t(rng() % s.spheres().size());
    const Sphere& sp = s.spheres()[k];
    const Vec3d c = dvec(sp.center), d = normalize(c);
    const Basis<double> b = orthonormal_basis(d);
    const double rad = 0.95 * sp.radius * std::sqrt(u(rng)), phi = u(rng) * 2 * kPi;
    const Vec3d target = c + (b.t * std::cos(phi) + b.b * std::sin(phi)) * rad;
    Ray r;
    r.org = Vec3f(0.0f);
    r.dir = Vec3f(normalize(target));
    const uint32_t fan[1] = {s.sphere_base() + k};
    f.add(r, fan);
  }
}

std::shared_ptr<Scene> tangent_scene() {
  auto s = std::make_shared<Scene>();
  s->add_sphere({{-6.0f, 0.0f, 0.0f}, 1.0f, 0});
  s->add_sphere({{-2.0f, 0.0f, 0.0f}, 0.25f, 0});
  s->add_quadric({Quadricf::ellipsoid({2.0f, 0.0f, 0.0f}, {1.0f, 0.5f, 1.5f}), 0});
  s->add_quadric({Quadricf::cylinder({6.0f, 0.0f, 0.0f}, 0.75f, 0.75f, 1.5f), 0});
  s->add_quadric({Quadricf::hyperboloid_one_sheet({10.0f, 0.0f, 0.0f}, 0.5f, 0.5f, 1.0f, 1.5f), 0});
  return s;
}

/// A double-precision surface point and unit normal of analytic primitive id, found by a ray
/// from outside its box towards a random point in it; false when that ray misses.
bool analytic_point(const Scene& s, uint32_t id, std::mt19937_64& rng, Vec3d& p, Vec3d& n) {
  const Box3f box = s.prim_bounds(id);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const Vec3d lo = dvec(box.lo), ext = dvec(box.extent());
  const Vec3d target = lo + Vec3d{ext.x * u(rng), ext.y * u(rng), ext.z * u(rng)};
  const Vec3d from = dvec(box.center()) + normalize(Vec3d{g(rng), g(rng), g(rng)}) * (2.0 * length(ext));
  RayT<double> r;
  r.org = from;
  r.dir = target - from;
  const auto ref = s.locate(id);
  if (ref.kind == PrimKind::sphere) {
    const Sphere& sp = s.spheres()[ref.shape];
    const Intersection<double> h = intersect_sphere_algebraic(r, dvec(sp.center), double(sp.radius));
    if (!h.hit) return false;
    p = r.at(h.t);
    n = normalize(p - dvec(sp.center));
    return true;
  }
  const Quadricf& qf = s.quadrics()[ref.shape].quadric;
  Quadricd q;
  q.A = qf.A; q.B = qf.B; q.C = qf.C; q.D = qf.D; q.E = qf.E; q.F = qf.F;
  q.G = qf.G; q.H = qf.H; q.I = qf.I; q.J = qf.J;
  q.center = dvec(qf.center);
  q.clip = {dvec(qf.clip.lo), dvec(qf.clip.hi)};
  const Intersection<double> h = intersect_quadric(r, q);
  if (!h.hit) return false;
  p = r.at(h.t);
  const Vec3d grad = q.gradient(p);
  if (!(length(grad) > 0.0)) return false;
  n = normalize(grad);
  return true;
}

void gen_tangent(Family& f, uint32_t n, std::mt19937_64& rng) {
  const Scene& s = *f.scene;
  const uint32_t first = s.sphere_base(), count = s.polygon_base() - first;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (uint32_t i = 0, tries = 0; i < n && tries < 20 * n; ++tries) {
    const uint32_t id = first + uint32_t(rng() % count);
    Vec3d p, nn;
    if (!analytic_point(s, id, rng, p, nn)) continue;
    const Basis<double> b = orthonormal_basis(nn);
    const double phi = u(rng) * 2 * kPi;
    const Vec3d t = b.t * std::cos(phi) + b.b * std::sin(phi);
    const double size = length(dvec(s.prim_bounds(id).extent()));
    const double eps = std::pow(10.0, -1.0 - 5.0 * u(rng)) * size * ((rng() & 1) ? 1.0 : -1.0);
    const Vec3d through = p + nn * eps;  // passes the surface at distance ~|eps|, outside or inside
    const uint32_t fan[1] = {id};
    f.add(make_ray(through - t * (2.0 * size), through), fan);
    ++i;
  }
}

/// Rays leaving surface points: from a point hit by an approaching ray (reference), computed as
/// the renderer computes it (Scene::surface), towards the reflection or the transmission side.
void gen_leaving(Family& raw, Family& offset, const Reference& ref, const Geom& g, uint32_t n,
                 std::mt19937_64& rng) {
  const Scene& s = *raw.scene;
  const uint32_t bounded = s.plane_base();
  if (bounded == 0) return;
  const double diag = g.diagonal();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (uint32_t i = 0, tries = 0; i < n && tries < 20 * n; ++tries) {
    const uint32_t id = uint32_t(rng() % bounded);
    Vec3d p, nn;
    if (id < s.triangle_count()) {
      nn = g.normal(id);
      if (length(nn) == 0.0) continue;
      p = g.point(id, rng);
    } else if (id < s.polygon_base()) {
      if (!analytic_point(s, id, rng, p, nn)) continue;
    } else {
      continue;
    }
    Family approach;
    approach.scene = raw.scene;
    add_approach(approach, p, nn, diag, rng, {});
    const Ray in = approach.rays[0];
    const ReferenceHit h = ref.intersect(in);
    if (!h.hit()) continue;
    const SurfacePoint sp = s.surface(in, Hit{float(h.t), h.prim_id, float(h.u), float(h.v)});
    Vec3f nf = sp.geometric_normal;
    if (dot(nf, in.dir) > 0.0f) nf = -nf;  // face-forwarded: towards the incoming ray's side
    const bool through = rng() & 1;
    const Vec3f side = through ? -nf : nf;
    const Vec3d d = around(dvec(side), rng);
    Ray r;
    r.org = sp.position;
    r.dir = Vec3f(d);
    raw.add(r);
    raw.source.push_back(h.prim_id);
    r.org = offset_ray_origin(sp.position, side);
    offset.add(r);
    offset.source.push_back(h.prim_id);
    ++i;
  }
}

/// A method's answer for one ray.
struct Outcome {
  bool hit = false;
  double t = kInf;
  uint32_t prim = kInvalidId;
  int n_hits = 0;  ///< fan primitives hit at the closest point (scalar methods)
};

bool is_planar(const Scene& s, uint32_t prim) {
  const PrimKind k = s.locate(prim).kind;
  return k == PrimKind::triangle || k == PrimKind::polygon || k == PrimKind::plane;
}

void classify(const Family& f, size_t i, const ReferenceHit& ref, const Outcome& m, double tol, Counts& c) {
  const Ray& r = f.rays[i];
  ++c.rays;
  auto fail = [&c](uint64_t& kind) {
    ++kind;
    ++c.failed;
  };
  if (f.invalid || !valid_ray(r)) {
    if (m.hit) fail(c.nan_hits);
    return;
  }
  if (m.hit && !std::isfinite(m.t)) return fail(c.nan_hits);
  if (m.hit && !(m.t >= r.tnear && m.t <= r.tfar)) return fail(c.out_of_interval);
  if (!f.judged[i]) return;
  if (!f.source.empty()) {  // leaving families: judged on self-hits only
    const uint32_t src = f.source[i];
    const double dist = m.t * length(dvec(r.dir));
    if (m.hit && m.prim == src && (is_planar(*f.scene, src) || dist < 1e-4 * f.diagonal)) fail(c.self_hits);
    return;
  }
  if (m.n_hits >= 2) ++c.double_hits;  // counted, not a failure: see Counts
  // An origin exactly on a surface (the reference hits at t = tnear; far from the origin the
  // rounded ray can land on the rounded mesh): hitting it and passing on are both defensible.
  if (ref.hit() && ref.t <= double(r.tnear)) return;
  if (!ref.hit()) {
    if (m.hit) fail(c.false_hits);
    return;
  }
  if (!m.hit) return fail(c.leaks);
  const double d = m.t - ref.t;
  if (std::abs(d) <= tol * std::abs(ref.t)) return;  // the same point (a tie when the primitive differs)
  if (m.prim == ref.prim_id) return fail(c.t_errors);
  if (d > 0) fail(c.leaks);
  else fail(c.false_hits);
}

/// A scalar routine of engine/geometry over one primitive kind.
struct ScalarMethod {
  std::string name;
  PrimKind kind;
  std::function<Intersection<float>(const Scene&, const Ray&, uint32_t)> test;
};

template <Intersection<float> (*Fn)(const Ray&, const Vec3f&, const Vec3f&, const Vec3f&)>
ScalarMethod triangle_method(const char* name) {
  return {name, PrimKind::triangle, [](const Scene& s, const Ray& r, uint32_t id) {
            const auto ref = s.locate(id);
            const TriangleMesh& m = s.meshes()[ref.shape];
            return Fn(r, m.vertex(ref.local, 0), m.vertex(ref.local, 1), m.vertex(ref.local, 2));
          }};
}

template <Intersection<float> (*Fn)(const Ray&, const Vec3f&, float)>
ScalarMethod sphere_method(const char* name) {
  return {name, PrimKind::sphere, [](const Scene& s, const Ray& r, uint32_t id) {
            const Sphere& sp = s.spheres()[s.locate(id).shape];
            return Fn(r, sp.center, sp.radius);
          }};
}

template <Intersection<float> (*Fn)(const Ray&, const Quadricf&)>
ScalarMethod quadric_method(const char* name) {
  return {name, PrimKind::quadric, [](const Scene& s, const Ray& r, uint32_t id) {
            return Fn(r, s.quadrics()[s.locate(id).shape].quadric);
          }};
}

const std::vector<ScalarMethod>& scalar_method_list() {
  static const std::vector<ScalarMethod> list = {
      triangle_method<&intersect_triangle_mt<float>>("triangle/mt"),
      triangle_method<&intersect_triangle_mt_epsilon<float>>("triangle/mt_epsilon"),
      triangle_method<&intersect_triangle_mt_normal<float>>("triangle/mt_normal"),
      triangle_method<&intersect_triangle_watertight<float>>("triangle/watertight"),
      sphere_method<&intersect_sphere_naive<float>>("sphere/naive"),
      sphere_method<&intersect_sphere_algebraic<float>>("sphere/stable"),
      sphere_method<&intersect_sphere_geometric<float>>("sphere/geometric"),
      quadric_method<&intersect_quadric_naive<float>>("quadric/naive"),
      quadric_method<&intersect_quadric<float>>("quadric/stable"),
  };
  return list;
}

/// Runs one family: the reference, every backend, every scalar method whose kind the fans hold.
void evaluate(const Family& f, const Reference& reference, const Options& o,
              std::map<std::string, std::unique_ptr<Backend>>& backends, std::vector<Result>& out) {
  if (f.rays.empty()) return;
  std::vector<ReferenceHit> ref(f.rays.size());
  reference.intersect(f.rays, ref);
  auto emit = [&](const std::string& method, const Counts& c) {
    out.push_back({f.name, f.param, f.exponent, f.has_exponent, method, c});
  };
  for (const std::string& name : o.backends) {
    auto& b = backends[name];
    if (!b) b = o.make_backend(name, *f.scene);
    std::vector<Hit> hits(f.rays.size());
    b->intersect(f.rays, hits, Coherence::incoherent);
    Counts c;
    for (size_t i = 0; i < f.rays.size(); ++i)
      classify(f, i, ref[i], {hits[i].hit(), hits[i].hit() ? double(hits[i].t) : kInf, hits[i].prim_id, 0},
               o.t_tolerance, c);
    emit(name, c);
  }
  if (!f.source.empty() || f.invalid) return;  // scalar methods: fan families only
  for (const ScalarMethod& sm : scalar_method_list()) {
    Counts c;
    c.double_measured = true;
    for (size_t i = 0; i < f.rays.size(); ++i) {
      const auto fan = f.fan_of(i);
      if (fan.empty()) continue;
      if (!std::all_of(fan.begin(), fan.end(), [&](uint32_t p) { return f.scene->locate(p).kind == sm.kind; })) continue;
      if (ref[i].hit() && std::find(fan.begin(), fan.end(), ref[i].prim_id) == fan.end()) continue;  // hidden
      std::vector<Intersection<float>> hs;
      Outcome m;
      for (uint32_t p : fan) {
        hs.push_back(sm.test(*f.scene, f.rays[i], p));
        if (hs.back().hit && hs.back().t < m.t) m = {true, hs.back().t, p, 0};
      }
      for (const auto& h : hs) m.n_hits += h.hit && std::abs(h.t - m.t) <= o.t_tolerance * std::abs(m.t);
      classify(f, i, ref[i], m, o.t_tolerance, c);
    }
    if (c.rays) emit(sm.name, c);
  }
}

std::string pow10_label(int k) { return "1e" + std::to_string(k); }

}  // namespace

std::vector<std::pair<std::string, std::string>> family_names() { return kFamilies; }

std::vector<std::string> scalar_methods() {
  std::vector<std::string> out;
  for (const ScalarMethod& m : scalar_method_list()) out.push_back(m.name);
  return out;
}

Scene transformed(const Scene& s, double scale, const Vec3d& off) {
  RP_CHECK(scale > 0.0 && std::isfinite(scale), "stability: scale ", scale, " must be finite and > 0");
  auto P = [&](const Vec3f& p) { return Vec3f(dvec(p) * scale + off); };
  Scene out;
  for (size_t i = 1; i < s.materials().size(); ++i) out.add_material(s.materials()[i]);
  for (TriangleMesh m : s.meshes()) {
    for (Vec3f& p : m.positions) p = P(p);
    out.add_mesh(std::move(m));
  }
  for (Sphere sp : s.spheres()) {
    sp.center = P(sp.center);
    sp.radius = float(double(sp.radius) * scale);
    out.add_sphere(sp);
  }
  for (QuadricShape q : s.quadrics()) {
    Quadricf& f = q.quadric;
    const double s2 = scale * scale;
    f.A = float(f.A / s2); f.B = float(f.B / s2); f.C = float(f.C / s2);
    f.D = float(f.D / s2); f.E = float(f.E / s2); f.F = float(f.F / s2);
    f.G = float(f.G / scale); f.H = float(f.H / scale); f.I = float(f.I / scale);
    f.center = P(f.center);
    f.clip = {P(f.clip.lo), P(f.clip.hi)};
    out.add_quadric(q);
  }
  for (const PolygonShape& pg : s.polygons()) {
    std::vector<Vec3f> v(s.polygon_vertices().begin() + pg.first, s.polygon_vertices().begin() + pg.first + pg.count);
    for (Vec3f& p : v) p = P(p);
    out.add_polygon(v, pg.material);
  }
  for (Plane pl : s.planes()) {
    pl.d = float(double(pl.d) * scale - dot(dvec(pl.normal), off));
    out.add_plane(pl);
  }
  for (PointLight l : s.point_lights()) {
    l.position = P(l.position);
    out.add_light(l);
  }
  for (const DirectionalLight& l : s.directional_lights()) out.add_light(l);
  if (s.camera()) {
    CameraDesc c = *s.camera();
    c.eye = P(c.eye);
    c.look_at = P(c.look_at);
    c.aperture = float(c.aperture * scale);
    c.focus_distance = float(c.focus_distance * scale);
    out.set_camera(c);
  }
  return out;
}

std::vector<Result> run(const Scene& base, const Options& o) {
  RP_CHECK(o.make_backend, "stability: no backend factory");
  RP_CHECK(o.rays >= 1 && o.rays <= 1u << 22, "stability: rays per family ", o.rays, " is out of range (1..4194304)");
  for (const std::string& name : o.families)
    RP_CHECK(std::any_of(kFamilies.begin(), kFamilies.end(), [&](const auto& f) { return f.first == name; }),
             "stability: unknown family '", name, "'");
  auto wanted = [&](const std::string& name) {
    return o.families.empty() || std::find(o.families.begin(), o.families.end(), name) != o.families.end();
  };
  std::vector<Result> out;
  const uint32_t n = o.rays;
  const Topology base_topology(base);

  // One scene at a time: its reference and backends are built once for all its families.
  auto scene_group = [&](const Reference& reference, std::vector<Family> families) {
    families.erase(std::remove_if(families.begin(), families.end(), [](const Family& f) { return f.rays.empty(); }),
                   families.end());
    if (families.empty()) return;
    std::map<std::string, std::unique_ptr<Backend>> backends;
    for (const Family& f : families) {
      if (o.progress) o.progress(f.name + (f.param.empty() ? "" : " " + f.param));
      evaluate(f, reference, o, backends, out);
    }
  };
  auto family = [&](const std::string& name, std::shared_ptr<const Scene> scene, const std::string& param = "",
                    int exponent = 0, bool has_exponent = false) {
    Family f;
    f.name = name;
    f.param = param;
    f.exponent = exponent;
    f.has_exponent = has_exponent;
    f.scene = std::move(scene);
    f.diagonal = scene_diagonal(*f.scene);
    return f;
  };
  auto rng_for = [&](const std::string& name) { return std::mt19937_64(fnv1a(name, o.seed)); };

  {  // the given scene
    auto scene = std::make_shared<const Scene>(base);
    const Topology& topo = base_topology;
    const Geom g{&base};
    std::vector<Family> fs;
    for (const char* name : {"edges", "vertices", "grazing", "axis_parallel", "nan_inf"}) {
      if (!wanted(name)) continue;
      Family f = family(name, scene);
      auto rng = rng_for(name);
      const std::string nm = name;
      if (nm == "edges") gen_edges(f, g, topo, n, rng);
      else if (nm == "vertices") gen_vertices(f, g, topo, n, rng);
      else if (nm == "grazing") gen_grazing(f, g, n, rng);
      else if (nm == "axis_parallel") gen_axis_parallel(f, g, topo, n, rng);
      else gen_nan_inf(f, g, n, rng);
      fs.push_back(std::move(f));
    }
    scene_group(Reference(*scene), std::move(fs));
  }
  // Families with a scene of their own, one scene each.
  struct Own {
    const char* name;
    std::function<std::shared_ptr<Scene>(std::mt19937_64&)> scene;
    std::function<void(Family&, uint32_t, std::mt19937_64&)> rays;
  };
  const Own own[] = {
      {"flat_boxes", [](std::mt19937_64&) { return flat_boxes_scene(); }, gen_flat_boxes},
      {"needles", needles_scene, gen_needles},
      {"far_spheres", far_spheres_scene, gen_far_spheres},
      {"tangent", [](std::mt19937_64&) { return tangent_scene(); }, gen_tangent},
  };
  for (const Own& fam : own) {
    if (!wanted(fam.name)) continue;
    auto rng = rng_for(fam.name);
    auto scene = fam.scene(rng);
    Family f = family(fam.name, scene);
    fam.rays(f, n, rng);
    scene_group(Reference(*scene), {std::move(f)});
  }
  // Moved and scaled copies of the scene: the same kinds of rays, and rays leaving surfaces.
  struct Transform {
    const char* family;
    int k;
  };
  std::vector<Transform> transforms;
  for (int k = 0; k <= 7; ++k) transforms.push_back({"translated", k});
  for (int k : {-6, -3, 3, 6}) transforms.push_back({"scaled", k});
  const bool leaving = wanted("leaving_raw") || wanted("leaving_offset");
  for (const Transform& tr : transforms) {
    const bool moved = std::string(tr.family) == "translated";
    if (!wanted(tr.family) && !leaving) continue;
    const double p = std::pow(10.0, tr.k);
    // Translation along a fixed, non-axis direction so every coordinate is large.
    const Vec3d offset = moved ? Vec3d{p, 0.75 * p, 0.5 * p} : Vec3d(0.0);
    const double scale = moved ? 1.0 : p;
    auto scene = std::make_shared<const Scene>(transformed(base, scale, offset));
    const Geom g{&base, scale, offset};
    const Reference reference(*scene);
    const std::string param = pow10_label(tr.k);
    std::vector<Family> fs;
    if (wanted(tr.family)) {
      Family f = family(tr.family, scene, param, tr.k, true);
      auto rng = rng_for(std::string(tr.family) + param);
      gen_edges(f, g, base_topology, n / 3, rng);
      gen_vertices(f, g, base_topology, n / 3, rng);
      gen_surface(f, g, n - 2 * (n / 3), rng);
      fs.push_back(std::move(f));
    }
    if (leaving) {
      const std::string where = std::string(moved ? "translated " : "scaled ") + param;
      Family raw = family("leaving_raw", scene, where, tr.k, true);
      Family off = family("leaving_offset", scene, where, tr.k, true);
      auto rng = rng_for("leaving" + where);
      gen_leaving(raw, off, reference, g, n, rng);
      if (wanted("leaving_raw")) fs.push_back(std::move(raw));
      if (wanted("leaving_offset")) fs.push_back(std::move(off));
    }
    scene_group(reference, std::move(fs));
  }
  return out;
}

void print_table(std::FILE* out, const std::vector<Result>& results) {
  std::fprintf(out, "%-15s %-14s %-20s %7s %9s %7s %7s %7s %7s %7s %7s %7s\n", "family", "param", "method", "rays",
               "fail %", "leaks", "false", "t err", "double", "self", "nan", "out");
  for (const Result& r : results) {
    const Counts& c = r.counts;
    const std::string dbl = c.double_measured ? std::to_string(c.double_hits) : "-";
    std::fprintf(out, "%-15s %-14s %-20s %7llu %9.4f %7llu %7llu %7llu %7s %7llu %7llu %7llu\n", r.family.c_str(),
                 r.param.empty() ? "-" : r.param.c_str(), r.method.c_str(), (unsigned long long)c.rays, 100.0 * c.rate(),
                 (unsigned long long)c.leaks, (unsigned long long)c.false_hits, (unsigned long long)c.t_errors,
                 dbl.c_str(), (unsigned long long)c.self_hits, (unsigned long long)c.nan_hits,
                 (unsigned long long)c.out_of_interval);
  }
}

std::string to_json(const std::vector<Result>& results, const std::string& scene_name, const Options& o) {
  nlohmann::json j;
  j["scene"] = scene_name;
  j["rays_per_family"] = o.rays;
  j["seed"] = o.seed;
  j["t_tolerance"] = o.t_tolerance;
  j["families"] = nlohmann::json::object();
  for (const auto& [name, what] : kFamilies) j["families"][name] = what;
  j["results"] = nlohmann::json::array();
  for (const Result& r : results) {
    const Counts& c = r.counts;
    nlohmann::json e = {{"family", r.family}, {"param", r.param}, {"method", r.method}, {"rays", c.rays},
                        {"failed", c.failed}, {"failure_rate", c.rate()}, {"leaks", c.leaks},
                        {"false_hits", c.false_hits}, {"t_errors", c.t_errors}, {"self_hits", c.self_hits},
                        {"nan_hits", c.nan_hits}, {"out_of_interval", c.out_of_interval}};
    e["double_hits"] = c.double_measured ? nlohmann::json(c.double_hits) : nlohmann::json(nullptr);
    if (r.has_exponent) e["exponent"] = r.exponent;
    j["results"].push_back(std::move(e));
  }
  return j.dump(2) + "\n";
}

}  // namespace rp::stability
