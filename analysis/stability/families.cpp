#include <algorithm>
#include <cmath>

#include "analysis/stability/family.h"
#include "base/error.h"
#include "base/offset.h"
#include "core/geometry/quadric.h"
#include "core/geometry/sphere.h"

namespace rp::stability {

namespace {

Vec3d dvec(const Vec3f& v) { return Vec3d(v); }

Ray make_ray(const Vec3d& from, const Vec3d& to) {
  Ray r;
  r.org = Vec3f(from);
  r.dir = Vec3f(to - from);
  return r;
}

/// A unit direction within 60 degrees of unit `n`.
Vec3d around(const Vec3d& n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double theta = u(rng) * kPi / 3, phi = u(rng) * 2 * kPi;
  const Basis<double> b = orthonormal_basis(n);
  return n * std::cos(theta) + (b.t * std::cos(phi) + b.b * std::sin(phi)) * std::sin(theta);
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
    const MeshView& m = s.meshes()[ref.shape];
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
  const Quadricd q = quadric_cast<double>(qf);
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
/// the renderer computes it (Scene::surface), towards the reflection or the transmission side;
/// from the point itself, or (`offset`) from it moved off the surface as the renderer does. The
/// random stream is used the same either way, so both versions of a seed leave the same points.
void gen_leaving(Family& f, bool offset, const Reference& ref, const Geom& g, uint32_t n, std::mt19937_64& rng) {
  const Scene& s = *f.scene;
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
    approach.scene = f.scene;
    add_approach(approach, p, nn, diag, rng, {});
    const Ray in = approach.rays[0];
    const ReferenceHit h = ref.intersect(in);
    if (!h.hit()) continue;
    const SurfacePoint sp = s.surface(in, to_hit(h));
    Vec3f nf = sp.geometric_normal;
    if (dot(nf, in.dir) > 0.0f) nf = -nf;  // face-forwarded: towards the incoming ray's side
    const bool through = rng() & 1;
    const Vec3f side = through ? -nf : nf;
    const Vec3d d = around(dvec(side), rng);
    Ray r;
    r.org = offset ? offset_ray_origin(sp.position, side) : sp.position;
    r.dir = Vec3f(d);
    f.add(r);
    f.source.push_back(h.prim_id);
    ++i;
  }
}

/// The translated and scaled families: rays at shared edges, vertices and surface points of
/// the moved copy, a third each.
void gen_moved(Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) {
  gen_edges(f, c.geom, c.topology, n / 3, rng);
  gen_vertices(f, c.geom, c.topology, n / 3, rng);
  gen_surface(f, c.geom, n - 2 * (n / 3), rng);
}

}  // namespace

Topology::Topology(const Scene& s) {
  std::vector<std::pair<uint64_t, uint32_t>> keyed;  // (edge key, triangle), sorted: deterministic
  for (uint32_t m = 0; m < s.meshes().size(); ++m) {
    const MeshView& mesh = s.meshes()[m];
    const uint32_t base = s.mesh_base(m);
    std::vector<std::vector<uint32_t>> around(mesh.positions.size());
    keyed.clear();
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
      for (int c = 0; c < 3; ++c) {
        const uint32_t i = mesh.triangles[t][c], j = mesh.triangles[t][(c + 1) % 3];
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

double scene_diagonal(const Scene& s) {
  const Box3f b = s.bounds();
  return b.empty() ? 1.0 : std::max(1e-30, length(dvec(b.extent())));
}

const std::vector<FamilySpec>& family_table() {
  using G = void (*)(Family&, const Context&, uint32_t, std::mt19937_64&);
  static const std::vector<FamilySpec> table = {
      {"edges", "rays aimed exactly at midpoints of shared mesh edges, from outside and inside", Where::given, nullptr,
       nullptr, G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_edges(f, c.geom, c.topology, n, rng); })},
      {"vertices", "rays aimed exactly at shared mesh vertices, from outside and inside", Where::given, nullptr, nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_vertices(f, c.geom, c.topology, n, rng); })},
      {"grazing", "rays at 1e-1..1e-6 rad to a triangle's plane, aimed inside it", Where::given, nullptr, nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_grazing(f, c.geom, n, rng); })},
      {"axis_parallel", "rays along +-x/y/z with +-0 components through mesh vertices, origins on the bounding box faces",
       Where::given, nullptr, nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_axis_parallel(f, c.geom, c.topology, n, rng); })},
      {"flat_boxes", "axis-aligned flat squares (zero-thickness boxes), rays across and inside their planes", Where::own,
       nullptr, [](std::mt19937_64&) { return flat_boxes_scene(); },
       G([](Family& f, const Context&, uint32_t n, std::mt19937_64& rng) { gen_flat_boxes(f, n, rng); })},
      {"needles", "needle and near-degenerate triangles (aspect 1e2..1e7), rays aimed at their centroids", Where::own,
       nullptr, needles_scene, G([](Family& f, const Context&, uint32_t n, std::mt19937_64& rng) { gen_needles(f, n, rng); })},
      {"nan_inf", "rays with a NaN or +-Inf in the origin, direction, tnear or tfar", Where::given, nullptr, nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_nan_inf(f, c.geom, n, rng); })},
      {"far_spheres", "spheres of radius 1 at distance 1e1..1e7, rays from the origin aimed inside their disc", Where::own,
       nullptr, far_spheres_scene,
       G([](Family& f, const Context&, uint32_t n, std::mt19937_64& rng) { gen_far_spheres(f, n, rng); })},
      {"tangent", "rays passing sphere and quadric surfaces tangentially, 1e-1..1e-6 (relative) to either side",
       Where::own, nullptr, [](std::mt19937_64&) { return tangent_scene(); },
       G([](Family& f, const Context&, uint32_t n, std::mt19937_64& rng) { gen_tangent(f, n, rng); })},
      {"translated", "the scene moved by 10^k, k = 0..7: rays at shared edges, vertices and surface points",
       Where::translated, nullptr, nullptr, gen_moved},
      {"scaled", "the scene scaled by 10^k, k = -6, -3, 3, 6: the same rays", Where::scaled, nullptr, nullptr, gen_moved},
      {"leaving_raw",
       "rays leaving computed hit points (reflection and transmission side), no offset, at every translation and scale",
       Where::moved, "leaving", nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_leaving(f, false, c.reference, c.geom, n, rng); })},
      {"leaving_offset", "the same rays with the origin offset as the renderer does (Waechter and Binder 2019)",
       Where::moved, "leaving", nullptr,
       G([](Family& f, const Context& c, uint32_t n, std::mt19937_64& rng) { gen_leaving(f, true, c.reference, c.geom, n, rng); })},
  };
  return table;
}

}  // namespace rp::stability
