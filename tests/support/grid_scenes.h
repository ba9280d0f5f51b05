#pragma once
// Seeded scenes of every primitive kind laid out on a 0.25 grid, and rays aimed at that grid:
// faces on box faces, shared vertices, exact duplicates (ties at equal t or distance), and
// axis-parallel rays with +-0 components. The hardest cases for a conservative traversal,
// first written for the double reference's tests (tests/engine/reference_test.cpp).

#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "base/math.h"
#include "core/geometry/quadric.h"
#include "core/ray.h"
#include "core/scene.h"

namespace rp::test {

inline float uniform(std::mt19937& rng, float lo, float hi) {
  return std::uniform_real_distribution<float>(lo, hi)(rng);
}
inline Vec3f uniform_vec(std::mt19937& rng, float lo, float hi) {
  return {uniform(rng, lo, hi), uniform(rng, lo, hi), uniform(rng, lo, hi)};
}
/// A multiple of 0.25 in [-3, 3]: lands exactly on grid vertices, faces and box bounds.
inline float grid(std::mt19937& rng) { return 0.25f * float(int(rng() % 25) - 12); }
inline Vec3f grid_vec(std::mt19937& rng) { return {grid(rng), grid(rng), grid(rng)}; }
inline float signed_zero(std::mt19937& rng) { return rng() % 2 ? 0.0f : -0.0f; }

inline TriangleMesh mesh_of(std::vector<Vec3f> positions, std::vector<uint32_t> indices, const char* name) {
  TriangleMesh m;
  m.name = name;
  m.positions = std::move(positions);
  m.indices = std::move(indices);
  return m;
}

/// Closed UV sphere (one vertex per pole), vertex coordinates rounded to multiples of
/// 2^-10 so that every edge midpoint is exactly representable.
inline TriangleMesh quantized_uv_sphere(int slices, int stacks, Vec3f centre, float radius) {
  const auto q = [](double x) { return float(std::round(x * 1024.0) / 1024.0); };
  std::vector<Vec3f> p{{centre.x, centre.y + q(radius), centre.z}};
  for (int j = 1; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const double th = kPi * j / stacks, ph = 2 * kPi * i / slices;
      p.push_back(centre + Vec3f{q(radius * std::sin(th) * std::cos(ph)), q(radius * std::cos(th)),
                                 q(radius * std::sin(th) * std::sin(ph))});
    }
  p.push_back({centre.x, centre.y - q(radius), centre.z});
  const uint32_t south = uint32_t(p.size() - 1);
  const auto ring = [&](int j, int i) { return uint32_t(1 + (j - 1) * slices + (i % slices)); };
  std::vector<uint32_t> idx;
  for (int i = 0; i < slices; ++i) idx.insert(idx.end(), {0u, ring(1, i + 1), ring(1, i)});
  for (int j = 1; j + 1 < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      idx.insert(idx.end(), {ring(j, i), ring(j, i + 1), ring(j + 1, i)});
      idx.insert(idx.end(), {ring(j, i + 1), ring(j + 1, i + 1), ring(j + 1, i)});
    }
  for (int i = 0; i < slices; ++i) idx.insert(idx.end(), {south, ring(stacks - 1, i), ring(stacks - 1, i + 1)});
  return mesh_of(std::move(p), std::move(idx), "uv_sphere");
}

/// A closed axis-aligned box of 12 triangles.
inline TriangleMesh box_mesh(Vec3f lo, Vec3f hi) {
  std::vector<Vec3f> p;
  for (int k = 0; k < 8; ++k) p.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
  std::vector<uint32_t> idx{0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return mesh_of(std::move(p), std::move(idx), "box");
}

/// Every kind of primitive, translated by `offset`: a triangle soup (random and on the 0.25
/// grid, so faces are axis-aligned and vertices shared), exact duplicates of some triangles
/// in a second mesh (ties), a closed box and sphere mesh, spheres, every quadric, a convex
/// and a star polygon, planes.
inline Scene random_scene(uint32_t seed, int soup, Vec3f offset) {
  std::mt19937 rng(seed);
  Scene s;
  std::vector<Vec3f> p;
  std::vector<uint32_t> idx;
  for (int t = 0; t < soup; ++t) {
    const bool on_grid = rng() % 3 == 0;
    const Vec3f a = on_grid ? grid_vec(rng) : uniform_vec(rng, -2.5f, 2.5f);
    for (int c = 0; c < 3; ++c) {
      Vec3f v = on_grid ? grid_vec(rng) : a + uniform_vec(rng, -0.6f, 0.6f);
      if (on_grid && rng() % 2) v[c % 3] = a[c % 3];  // axis-aligned faces
      p.push_back(offset + (c == 0 ? a : v));
      idx.push_back(uint32_t(p.size() - 1));
    }
  }
  s.add_mesh(mesh_of(p, idx, "soup"));
  std::vector<uint32_t> dup;
  for (uint32_t t = 0; t < uint32_t(soup); t += 7) dup.insert(dup.end(), {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]});
  s.add_mesh(mesh_of(p, dup, "duplicates"));
  s.add_mesh(box_mesh(offset + Vec3f{-0.5f, -0.5f, -0.5f}, offset + Vec3f{0.75f, 0.5f, 1.0f}));
  s.add_mesh(quantized_uv_sphere(12, 6, offset + Vec3f{1.5f, 1.5f, -1.0f}, 0.75f));

  for (int i = 0; i < 3; ++i) s.add_sphere({offset + uniform_vec(rng, -2, 2), uniform(rng, 0.1f, 0.8f), 0});
  s.add_sphere({offset + Vec3f{0.25f, -1.0f, 0.5f}, 0.5f, 0});  // bounds on the grid
  using Qf = Quadric<float>;
  const auto c = [&] { return offset + uniform_vec(rng, -2, 2); };
  const int axis = int(rng() % 3);
  s.add_quadric({Qf::ellipsoid(c(), {0.5f, 0.3f, 0.4f}), 0});
  s.add_quadric({Qf::cylinder(c(), 0.3f, 0.2f, 0.5f, axis), 0});
  s.add_quadric({Qf::cone(c(), 0.4f, 0.4f, 0.6f, axis), 0});
  s.add_quadric({Qf::hyperboloid_one_sheet(c(), 0.2f, 0.2f, 0.3f, 0.4f, axis), 0});
  s.add_quadric({Qf::hyperboloid_two_sheets(c(), 0.2f, 0.2f, 0.2f, 0.5f, axis), 0});
  s.add_quadric({Qf::paraboloid(c(), 0.3f, 0.3f, 0.5f, axis), 0});
  const std::vector<Vec3f> quad{offset + Vec3f{-1.5f, -1.5f, -1.5f}, offset + Vec3f{-0.5f, -1.5f, -1.5f},
                                offset + Vec3f{-0.5f, -0.5f, -1.5f}, offset + Vec3f{-1.5f, -0.5f, -1.5f}};
  s.add_polygon(quad, 0);
  std::vector<Vec3f> star;
  for (int k = 0; k < 10; ++k) {
    const float a = float(kPi) * (0.5f + float(k) / 5.0f), r = (k % 2 == 0) ? 0.7f : 0.3f;
    const float x = r * std::cos(a), z = r * std::sin(a);
    star.push_back(offset + Vec3f{1.0f + x, 0.3f * x - 0.5f, 1.2f + z});
  }
  s.add_polygon(star, 0);
  const Vec3f n = normalize(Vec3f{0.1f, 1.0f, 0.05f});
  s.add_plane({n, 2.8f - dot(n, offset), 0});
  s.add_plane({{0.0f, 0.0f, 1.0f}, -(offset.z + 3.0f), 0});  // z = offset.z + 3, on the grid
  return s;
}

/// Random rays (through the scene), axis-parallel rays from grid points with +-0 in the other
/// components, rays aimed at grid points, a quarter with finite tfar, some with tnear > 0.
inline std::vector<Ray> grid_and_random_rays(uint32_t seed, int count, Vec3f offset) {
  std::mt19937 rng(seed);
  std::vector<Ray> rays;
  for (int n = 0; n < count; ++n) {
    Ray r;
    switch (n % 3) {
      case 0: {
        r.org = offset + uniform_vec(rng, -4, 4);
        const Vec3f target = offset + uniform_vec(rng, -2.5f, 2.5f);
        r.dir = (target - r.org) * uniform(rng, 0.1f, 10.0f);
        break;
      }
      case 1: {
        const int axis = int(rng() % 3);
        r.org = offset + grid_vec(rng);
        r.org[axis] = offset[axis] + (rng() % 2 ? 4.0f : -4.0f);
        for (int k = 0; k < 3; ++k) r.dir[k] = signed_zero(rng);
        r.dir[axis] = (r.org[axis] > offset[axis] ? -1.0f : 1.0f) * (rng() % 2 ? 1.0f : 0.5f);
        if (rng() % 4 == 0) r.org[axis] = offset[axis] + grid(rng);  // starts inside, maybe on a face
        break;
      }
      default: {
        r.org = offset + grid_vec(rng) + Vec3f{0.0f, 0.0f, 5.0f};
        r.dir = offset + grid_vec(rng) - r.org;
        break;
      }
    }
    if (rng() % 4 == 0) r.tfar = uniform(rng, 0.5f, 6.0f);
    if (rng() % 5 == 0) r.tnear = uniform(rng, 0.01f, 0.5f);
    if (!is_finite(r.dir) || (r.dir.x == 0.0f && r.dir.y == 0.0f && r.dir.z == 0.0f)) r.dir = {0.0f, 0.0f, 1.0f};
    rays.push_back(r);
  }
  return rays;
}

}  // namespace rp::test
