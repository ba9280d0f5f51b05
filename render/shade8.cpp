// shade_batch8 (shade_group.h): a batch shaded eight rays at a time. A group of 8 is read as
// vectors: rays, hits and paths transposed from their records; its triangles' corners, vertex
// normals and materials broadcast when every hit is on one triangle, gathered when they share
// a mesh, read lane by lane when they do not. Its surface points run on float8 lanes
// (surface_lanes.h: triangle_point, instance_point for an instance's triangle, sphere_point,
// plane_point, quadric_point where the group's quadric hits share one quadric; hits on
// several quadrics come from Scene::surface lane by lane), then all of shading.h, and its
// shadow rays and waiting contributions are transposed back into records and appended in lane
// order. The last few rays of a batch go a ray at a time (shade_ray): the same bits either
// way. Built for AVX2+FMA; the renderer calls it only on such a CPU (shade_batch_function).

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "core/surface_lanes.h"
#include "render/shade_group.h"
#include "render/shading.h"
#include "simd/float8.h"
#include "simd/lanes8.h"

namespace rp {

namespace {

using simd::float8;
using simd::int8;
using simd::mask8;
using V8 = Vec3<float8>;

/// The corners, vertex normals and materials of 8 triangle hits (lanes `hit`).
struct TriangleInputs {
  V8 c[3], n[3];
  mask8 has_normals;
  int8 material;
};

/// The triangles [begin, end) of one mesh: the last one a batch's hits were found in, so
/// that most groups need no Scene::locate.
struct MeshRange {
  uint32_t mesh = 0, begin = 0, end = 0;
  /// The mesh of triangle `id`, remembered.
  uint32_t of(const Scene& scene, uint32_t id) {
    if (id < begin || id >= end) {
      mesh = scene.locate(id).shape;
      begin = scene.mesh_base(mesh);
      end = begin + scene.meshes()[mesh].triangle_count();
    }
    return mesh;
  }
};

/// Lane l of out[k] is word k of item index[l] of `items` (3 words each).
template <typename T>
void gather_records3(const Strided<T>& items, const int32_t index[8], float8 out[3]) {
  static_assert(sizeof(T) == 12);
  simd::gather_records3(items.data(), items.stride(), items.size(), index, out);
}

/// The face materials of triangles `local`: one gather when they are contiguous, else a load
/// per lane (a gather's scale is 1, 2, 4 or 8, and index * stride could overflow its lanes).
int8 face_materials(const Strided<uint32_t>& materials, const int8& local) {
  if (materials.stride() == sizeof(uint32_t))
    return simd::gather(reinterpret_cast<const int32_t*>(materials.data()), local);
  alignas(32) int32_t index[8], out[8];
  local.store_aligned(index);
  for (int l = 0; l < 8; ++l) out[l] = int32_t(materials[uint32_t(index[l])]);
  return int8::load_aligned(out);
}

/// The lanes `lanes` of mesh `mesh` (its triangles from `begin`), gathered as vectors into
/// `in` (every lane of it when `all`, else only those): the index triples, then each
/// corner's position and normal, read as 16-byte records and transposed. Written in place: a
/// TriangleInputs returned and copied went through the stack 16 bytes at a time and was read
/// back 32 at a time, which no store can forward.
void mesh_inputs(const Scene& scene, uint32_t mesh, uint32_t begin, const float8& prim, uint32_t lanes, bool all,
                 TriangleInputs& in) {
  const MeshView& m = scene.meshes()[mesh];
  const mask8 on = simd::mask_from_bits(lanes);
  const auto put = [&](V8& to, const V8& v) { to = all ? v : select<float8>(on, v, to); };
  const int8 local =
      simd::as_int(xsimd::select(on, simd::as_float(simd::as_int(prim) - int8(int32_t(begin))), float8(0.0f)));
  alignas(32) int32_t triangle[8], corner[3][8];
  local.store_aligned(triangle);
  float8 rows[3];
  gather_records3(m.triangles, triangle, rows);
  for (int k = 0; k < 3; ++k) simd::as_int(rows[k]).store_aligned(corner[k]);
  for (int k = 0; k < 3; ++k) {
    gather_records3(m.positions, corner[k], rows);
    put(in.c[k], {rows[0], rows[1], rows[2]});
    if (!m.normals.empty()) {
      gather_records3(m.normals, corner[k], rows);
      put(in.n[k], {rows[0], rows[1], rows[2]});
    } else {
      put(in.n[k], V8(Vec3f{0.0f}));
    }
  }
  const mask8 normals = simd::mask_from_bits(m.normals.empty() ? 0u : lanes);
  in.has_normals = all ? normals : (in.has_normals || normals);
  const int8 material = m.face_materials.empty() ? int8(int32_t(m.material)) : face_materials(m.face_materials, local);
  in.material = all ? material : simd::as_int(xsimd::select(on, simd::as_float(material), simd::as_float(in.material)));
}

/// Broadcasts them when every hit is on one triangle (as a packet's rays on a large triangle
/// are), else gathers them mesh by mesh (mesh_inputs; one mesh for most groups). The same
/// bits each way: only the hit lanes are read.
TriangleInputs triangle_inputs(const Scene& scene, const float8& prim, uint32_t hit, MeshRange& range) {
  alignas(32) uint32_t ids[8];
  simd::as_int(prim).store_aligned(reinterpret_cast<int32_t*>(ids));
  const uint32_t first = ids[std::countr_zero(hit)];
  const bool one_triangle = (simd::movemask(simd::bits_equal(prim, first)) & hit) == hit;
  TriangleInputs in;  // one object returned (so no copy)
  if (one_triangle) {
    const uint32_t mesh = range.of(scene, first);
    const MeshView& m = scene.meshes()[mesh];
    const uint32_t local = first - range.begin;
    const TriangleIndices& idx = m.triangles[local];
    for (int k = 0; k < 3; ++k) {
      in.c[k] = V8(m.positions[idx[k]]);
      in.n[k] = m.normals.empty() ? V8(Vec3f{0.0f}) : V8(m.normals[idx[k]]);
    }
    in.has_normals = simd::mask_from_bits(m.normals.empty() ? 0u : 0xffu);
    in.material = int8(int32_t(m.face_materials.empty() ? m.material : m.face_materials[local]));
    return in;
  }
  for (uint32_t left = hit; left;) {
    const uint32_t mesh = range.of(scene, ids[std::countr_zero(left)]);
    const uint32_t lanes =
        left & simd::movemask(simd::bits_below(prim, range.end)) & ~simd::movemask(simd::bits_below(prim, range.begin));
    mesh_inputs(scene, mesh, range.begin, prim, lanes, left == hit, in);  // the first mesh writes every lane
    left &= ~lanes;
  }
  return in;
}

/// The terms of materials `id` (one per lane), broadcast when every hit lane has the same one.
MaterialLanes<float8> material_inputs(const ShadeScene& s, const int8& id, uint32_t hit) {
  alignas(32) int32_t ids[8];
  id.store_aligned(ids);
  const int32_t first = ids[std::countr_zero(hit)];
  const bool same = (simd::movemask(simd::bits_equal(simd::as_float(id), uint32_t(first))) & hit) == hit;
  using R = ShadeScene::Row;
  const int8 safe =
      same ? int8(first)
           : simd::as_int(xsimd::select(simd::mask_from_bits(hit), simd::as_float(id), simd::as_float(int8(first))));
  auto row = [&](R r) { return same ? float8(s.rows[r][size_t(first)]) : simd::gather(s.rows[r].data(), safe); };
  return {{row(R::kd_x), row(R::kd_y), row(R::kd_z)},
          {row(R::ks_x), row(R::ks_y), row(R::ks_z)},
          {row(R::ke_x), row(R::ke_y), row(R::ke_z)},
          row(R::shininess),
          row(R::mirror),
          row(R::opacity)};
}

/// Appends the lanes `lit` of shadow rays (origin, tnear 0, to_light, tfar) and their waiting
/// contributions, in lane order.
void append_light(const V8& origin, const V8& to_light, float tfar, const float8& slot, const V8& contribution,
                  uint32_t lit, ShadowQueue& q) {
  if (!lit) return;
  static_assert(sizeof(Ray) == 32 && sizeof(Pending) == 16);
  float8 r[8] = {origin.x, origin.y, origin.z, float8(0.0f), to_light.x, to_light.y, to_light.z, float8(tfar)};
  simd::transpose8x8(r);
  const float8 p[4] = {slot, contribution.x, contribution.y, contribution.z};
  alignas(32) float records[32];
  simd::store_records4(p, records);
  Ray* rays = q.rays.data() + q.count;
  Pending* pending = q.pending.data() + q.count;
  q.count += size_t(std::popcount(lit));
  for (uint32_t b = lit; b; b &= b - 1) {
    const int lane = std::countr_zero(b);
    r[lane].store_unaligned(&(rays++)->org.x);
    std::memcpy(static_cast<void*>(pending++), records + 4 * lane, sizeof(Pending));
  }
}

/// Lane `lane` of v.
Vec3f lane_of(const V8& v, int lane) { return {v.x.get(size_t(lane)), v.y.get(size_t(lane)), v.z.get(size_t(lane))}; }

/// The surface points and materials of the analytic hits `lanes` (Scene::surface, lane by
/// lane), and the triangle hits' material ids where `triangle` (others: 0).
struct AnalyticInputs {
  PointLanes<float8> p;
  int8 material;
};
AnalyticInputs analytic_inputs(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> hits, size_t base,
                               uint32_t lanes) {
  simd::Spill<9> s;
  alignas(32) int32_t material[8] = {};
  for (int lane = 0; lane < 8; ++lane) {
    const SurfacePoint sp = (lanes >> lane & 1u) ? scene.surface(rays[base + size_t(lane)], hits[base + size_t(lane)])
                                                 : SurfacePoint{{}, {0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 1.0f}, 0};
    const Vec3f v[3] = {sp.position, sp.geometric_normal, sp.shading_normal};
    for (int k = 0; k < 3; ++k) {
      s.lanes[3 * k][lane] = v[k].x;
      s.lanes[3 * k + 1][lane] = v[k].y;
      s.lanes[3 * k + 2][lane] = v[k].z;
    }
    material[lane] = int32_t(sp.material);
  }
  return {{{s.load(0), s.load(1), s.load(2)}, {s.load(3), s.load(4), s.load(5)}, {s.load(6), s.load(7), s.load(8)}},
          int8::load_aligned(material)};
}

/// The analytic hits `lanes` (prim ids `prim`) by kind, from the ids' ranges: per lane a
/// sphere's centre and radius or a plane's (or a polygon's) normal and d, and the material,
/// gathered from ShadeScene's shape rows; the quadric when every quadric lane has the same one.
struct ShapeInputs {
  uint32_t sphere = 0, flat = 0;              ///< lanes on a sphere, on a plane or a polygon
  uint32_t quadric = 0;                       ///< lanes on a quadric
  const QuadricShape* one_quadric = nullptr;  ///< theirs, when they share it
  V8 a;                                       ///< centre or normal
  float8 b;                                   ///< radius or d
  int8 material;
};
ShapeInputs shape_inputs(const ShadeScene& s, const float8& prim, uint32_t lanes) {
  const Scene& scene = s.scene;
  ShapeInputs in;
  const uint32_t below_quadrics = simd::movemask(simd::bits_below(prim, scene.quadric_base()));
  const uint32_t below_polygons = simd::movemask(simd::bits_below(prim, scene.polygon_base()));
  in.sphere = lanes & below_quadrics;
  in.quadric = lanes & below_polygons & ~below_quadrics;
  in.flat = lanes & ~below_polygons;
  // Each lane's row; lanes outside `lanes` read the first one's.
  const float8 first = simd::broadcast_lane(prim, std::countr_zero(lanes));
  const int8 row =
      simd::as_int(xsimd::select(simd::mask_from_bits(lanes), prim, first)) - int8(int32_t(scene.sphere_base()));
  using R = ShadeScene::ShapeRow;
  in.a = {simd::gather(s.shape_rows[R::shape_ax].data(), row), simd::gather(s.shape_rows[R::shape_ay].data(), row),
          simd::gather(s.shape_rows[R::shape_az].data(), row)};
  in.b = simd::gather(s.shape_rows[R::shape_b].data(), row);
  in.material = simd::gather(s.shape_material.data(), row);
  if (in.quadric) {
    alignas(32) int32_t rows[8];
    row.store_aligned(rows);
    const int32_t q = rows[std::countr_zero(in.quadric)];
    bool one = true;
    for (uint32_t b = in.quadric; b; b &= b - 1) one = one && rows[std::countr_zero(b)] == q;
    if (one) in.one_quadric = &scene.quadrics()[size_t(q) - (scene.quadric_base() - scene.sphere_base())];
  }
  return in;
}

/// The lanes `lanes` of `p`, the object-space points of hits on instances' triangles (rays
/// `org`, `dir` at `t`), in world space as Scene::instance_surface makes them: fixed along the
/// object-space ray, then mapped by each lane's instance.
PointLanes<float8> instance_points(const Scene& scene, std::span<const Hit> hits, size_t base, uint32_t lanes,
                                   const V8& org, const V8& dir, const float8& t, const PointLanes<float8>& p) {
  const uint32_t first = hits[base + size_t(std::countr_zero(lanes))].instance_id;
  bool one = true;
  for (uint32_t b = lanes; b; b &= b - 1) one = one && hits[base + size_t(std::countr_zero(b))].instance_id == first;
  Affine3<float8> to_world, to_object;
  float8 orientation;
  if (one) {
    const Instance& in = scene.instances()[first];
    to_world = Affine3<float8>(in.object_to_world);
    to_object = Affine3<float8>(in.world_to_object);
    orientation = float8(in.orientation);
  } else {
    simd::Spill<25> s;  // object_to_world's 12 rows, world_to_object's 12, the orientation
    for (int lane = 0; lane < 8; ++lane) {
      const uint32_t id = (lanes >> lane & 1u) ? hits[base + size_t(lane)].instance_id : first;
      const Instance& in = scene.instances()[id];
      for (int k = 0; k < 12; ++k) {
        s.lanes[k][lane] = in.object_to_world.m[k / 4][k % 4];
        s.lanes[12 + k][lane] = in.world_to_object.m[k / 4][k % 4];
      }
      s.lanes[24][lane] = in.orientation;
    }
    for (int k = 0; k < 12; ++k) {
      to_world.m[k / 4][k % 4] = s.load(k);
      to_object.m[k / 4][k % 4] = s.load(12 + k);
    }
    orientation = s.load(24);
  }
  V8 object_org, object_dir;
  object_ray_fused(to_object, org, dir, object_org, object_dir);
  PointLanes<float8> local = p;
  fix_degenerate_normal<float8>(local, object_org, object_dir, t);
  const PointLanes<float8> world = instance_point<float8>(local, to_world, to_object, orientation);
  const mask8 take = simd::mask_from_bits(lanes);
  return {select<float8>(take, world.position, p.position),
          select<float8>(take, world.geometric_normal, p.geometric_normal),
          select<float8>(take, world.shading_normal, p.shading_normal)};
}

/// Rays [base, base + 8) of the batch: the triangle hits' surface points on 8 lanes (those of
/// `instanced` on an instance's triangle, mapped into the world), the other hits' from
/// Scene::surface, then the shading of every hit on 8 lanes.
void shade8(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits, const float8 hit_rows[4],
            const float8 path_rows[4], size_t base, uint32_t live, uint32_t hit, uint32_t triangle, uint32_t instanced,
            bool bounce, MeshRange& range, ShadeOut& out) {
  const Scene& scene = s.scene;
  float8 ray_rows[8];
  simd::load_transposed8x8(&rays[base].org.x, ray_rows);
  const V8 org{ray_rows[0], ray_rows[1], ray_rows[2]}, dir{ray_rows[4], ray_rows[5], ray_rows[6]};
  const V8 weight{path_rows[1], path_rows[2], path_rows[3]};
  alignas(32) uint32_t slot[8];
  simd::as_int(path_rows[0]).store_aligned(reinterpret_cast<int32_t*>(slot));

  V8 emitted{};
  ShadedHit<float8> h;
  PointLanes<float8> p;
  MaterialLanes<float8> m;
  int8 material(0);
  if (hit) {
    const uint32_t analytic = hit & ~triangle;
    if (triangle) {
      const TriangleInputs t = triangle_inputs(scene, hit_rows[1], triangle, range);
      p = triangle_point<float8>(t.c, t.n, t.has_normals, hit_rows[2], hit_rows[3]);
      material = t.material;
      if (instanced) p = instance_points(scene, hits, base, instanced, org, dir, hit_rows[0], p);
    }
    // Spheres, planes, polygons and one quadric on 8 lanes (sphere_point, plane_point,
    // quadric_point: Scene::surface's own code); several quadrics through Scene::surface.
    const ShapeInputs shapes = analytic ? shape_inputs(s, hit_rows[1], analytic) : ShapeInputs{};
    // The lanes `lanes` take the points `q` and the materials `mat`.
    const auto take = [&](uint32_t lanes, const PointLanes<float8>& q, const int8& mat) {
      const mask8 on = simd::mask_from_bits(lanes);
      p = {select<float8>(on, q.position, p.position), select<float8>(on, q.geometric_normal, p.geometric_normal),
           select<float8>(on, q.shading_normal, p.shading_normal)};
      material = simd::as_int(xsimd::select(on, simd::as_float(mat), simd::as_float(material)));
    };
    if (shapes.sphere)
      take(shapes.sphere, sphere_point<float8>(org, dir, hit_rows[0], shapes.a, shapes.b), shapes.material);
    if (shapes.flat) take(shapes.flat, plane_point<float8>(org, dir, hit_rows[0], shapes.a, shapes.b), shapes.material);
    if (shapes.one_quadric)  // one quadric's lanes on 8 lanes too (quadric_point)
      take(shapes.quadric, quadric_point<float8>(org, dir, hit_rows[0], shapes.one_quadric->quadric), shapes.material);
    if (const uint32_t quadric = shapes.one_quadric ? 0u : shapes.quadric) {  // several quadrics: Scene::surface
      const AnalyticInputs a = analytic_inputs(scene, rays, hits, base, quadric);
      take(quadric, a.p, a.material);
    }
    fix_degenerate_normal<float8>(p, org, dir, hit_rows[0]);  // as Scene::surface (a no-op on its own points)
    m = material_inputs(s, material, hit);
    h = shade_hit<float8>(dir, p, m, weight);
    emitted = h.emitted;
  }
  // Colours lane by lane: the sky for a miss, the unlit terms for a hit.
  alignas(32) float e[3][8];
  emitted.x.store_aligned(e[0]);
  emitted.y.store_aligned(e[1]);
  emitted.z.store_aligned(e[2]);
  for (uint32_t b = live; b; b &= b - 1) {
    const int lane = std::countr_zero(b);
    Vec3f& c = out.colour[slot[lane]];
    if (hit >> lane & 1u) {
      c += Vec3f{e[0][lane], e[1][lane], e[2][lane]};
    } else {
      c += mul(lane_of(weight, lane), sky(rays[base + size_t(lane)].dir));
    }
  }
  if (!hit) return;
  size_t l = 0;
  for (const PointLight& pl : scene.point_lights()) {
    V8 to_light;
    const LightTerm<float8> t = point_light_term<float8>(h, m, weight, pl, to_light);
    append_light(h.origin, to_light, s.shadow_tfar[l], path_rows[0], t.contribution, simd::movemask(t.lit) & hit,
                 out.shadow[l]);
    ++l;
  }
  for (const DirectionalLight& dl : scene.directional_lights()) {
    const LightTerm<float8> t = directional_light_term<float8>(h, m, weight, dl);
    const V8 to_light{float8(-dl.direction.x), float8(-dl.direction.y), float8(-dl.direction.z)};
    append_light(h.origin, to_light, s.shadow_tfar[l], path_rows[0], t.contribution, simd::movemask(t.lit) & hit,
                 out.shadow[l]);
    ++l;
  }
  if (!bounce || !s.any_bounce) return;
  alignas(32) int32_t ids[8];
  material.store_aligned(ids);
  const uint32_t back = simd::movemask(h.back);
  for (uint32_t b = hit; b; b &= b - 1) {
    const int lane = std::countr_zero(b);
    if (!s.bounces[size_t(ids[lane])]) continue;
    out.bounces.push_back({uint32_t(base) + uint32_t(lane), lane_of(p.position, lane), lane_of(h.ng, lane),
                           lane_of(h.d, lane), lane_of(h.origin, lane), bool(back >> lane & 1u), uint32_t(ids[lane])});
  }
}

}  // namespace

void shade_batch8(const ShadeScene& s, std::span<const Ray> rays, std::span<const Hit> hits,
                  std::span<const PathState> paths, bool bounce, ShadeOut& out) {
  static_assert(sizeof(Hit) == 20 && offsetof(Hit, prim_id) == 4 && offsetof(Hit, v) == 12 && sizeof(PathState) == 16);
  const size_t n = rays.size();
  MeshRange range;
  size_t base = 0;
  for (; base + 8 <= n; base += 8) {
    float8 hit_rows[4], path_rows[4];  // t, prim, u, v; slot, weight
    simd::load_records4(&hits[base].t, hit_rows, sizeof(Hit) / sizeof(float));
    simd::load_records4(reinterpret_cast<const float*>(&paths[base]), path_rows);
    const uint32_t live = ~simd::movemask(simd::bits_equal(path_rows[0], kInvalidId)) & 0xffu;
    const uint32_t hit = ~simd::movemask(simd::bits_equal(hit_rows[1], kInvalidId)) & live;
    const uint32_t triangle = simd::movemask(simd::bits_below(hit_rows[1], s.scene.triangle_count())) & hit;
    uint32_t instanced = 0;  // the triangle hits on an instance
    if (!s.scene.instances().empty())
      for (uint32_t b = triangle; b; b &= b - 1)
        if (hits[base + size_t(std::countr_zero(b))].instance_id != kNoInstance) instanced |= b & (~b + 1);
    shade8(s, rays, hits, hit_rows, path_rows, base, live, hit, triangle, instanced, bounce, range, out);
  }
  for (size_t i = base; i < n; ++i) shade_ray(s, rays[i], hits[i], paths[i], uint32_t(i), bounce, out);
}

}  // namespace rp
