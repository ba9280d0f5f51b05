#include "analysis/stability/judge.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/geometry/quadric.h"
#include "core/geometry/sphere.h"
#include "core/geometry/triangle.h"

namespace rp::stability {

namespace {

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
    const double dist = m.t * length(Vec3d(r.dir));
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

/// A scalar routine of core/geometry/ over one primitive kind.
struct ScalarMethod {
  std::string name;
  PrimKind kind;
  std::function<Intersection<float>(const Scene&, const Ray&, uint32_t)> test;
};

template <Intersection<float> (*Fn)(const Ray&, const Vec3f&, const Vec3f&, const Vec3f&)>
ScalarMethod triangle_method(const char* name) {
  return {name, PrimKind::triangle, [](const Scene& s, const Ray& r, uint32_t id) {
            const auto ref = s.locate(id);
            const MeshView& m = s.meshes()[ref.shape];
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

}  // namespace

std::vector<std::string> scalar_method_names() {
  std::vector<std::string> out;
  for (const ScalarMethod& m : scalar_method_list()) out.push_back(m.name);
  return out;
}

void evaluate(const Family& f, const Reference& reference, const Options& o,
              std::map<std::string, MethodBackend>& backends, std::vector<Result>& out) {
  if (f.rays.empty()) return;
  std::vector<ReferenceHit> ref(f.rays.size());
  reference.intersect(f.rays, ref);
  auto emit = [&](const std::string& method, const Counts& c) {
    out.push_back({f.name, f.param, f.exponent, f.has_exponent, method, c});
  };
  for (const std::string& name : o.backends) {
    auto& b = backends[name];
    if (!b.backend) b = o.make_backend(name, *f.scene);
    std::vector<Hit> hits(f.rays.size());
    b.backend->intersect(f.rays, hits, b.coherence);
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

}  // namespace rp::stability
