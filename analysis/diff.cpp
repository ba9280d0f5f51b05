#include "analysis/diff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/error.h"

namespace rp {

const char* to_string(DiffClass c) {
  switch (c) {
    case DiffClass::agree: return "agree";
    case DiffClass::tie: return "tie";
    case DiffClass::hit_miss: return "hit/miss";
    case DiffClass::wrong_prim: return "wrong primitive";
    case DiffClass::t_error: return "t error";
  }
  return "?";
}

double DiffResult::agreement() const {
  return rays == 0 ? 1.0 : double(count[size_t(DiffClass::agree)] + count[size_t(DiffClass::tie)]) / double(rays);
}

namespace {

bool close(double a, double b, double rel) { return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b)); }

/// The same primitive in the same placement: an instanced mesh's triangle hit through two
/// instances is two different primitives of the world.
template <typename A, typename B>
bool same_primitive(const A& a, const B& b) {
  return a.prim_id == b.prim_id && a.instance_id == b.instance_id;
}

DiffClass classify(const Hit& a, const Hit& b, const DiffOptions& o) {
  if (!a.hit() && !b.hit()) return DiffClass::agree;
  if (a.hit() != b.hit()) return DiffClass::hit_miss;
  if (same_primitive(a, b)) return close(a.t, b.t, o.t_tolerance) ? DiffClass::agree : DiffClass::t_error;
  return close(a.t, b.t, o.tie_tolerance) ? DiffClass::tie : DiffClass::wrong_prim;
}

/// The reference supports a backend's answer when it misses where the reference misses, or
/// hits the reference's primitive (in the same instance) at a close t, or ties with it.
bool supported(const Hit& h, const ReferenceHit& r, const DiffOptions& o) {
  if (!h.hit() || !r.hit()) return h.hit() == r.hit();
  if (same_primitive(h, r)) return close(h.t, r.t, o.t_tolerance);
  return close(h.t, r.t, o.tie_tolerance);
}

ErrorSamples error_samples(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> hits,
                           std::span<const ReferenceHit> ref) {
  ErrorSamples s;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].hit() || !same_primitive(hits[i], ref[i])) continue;
    s.t_rel.push_back(std::abs(double(hits[i].t) - ref[i].t) / std::max(ref[i].t, 1e-30));
    const Vec3f na = scene.surface(rays[i], hits[i]).geometric_normal;
    const Vec3f nr = scene.surface(rays[i], to_hit(ref[i])).geometric_normal;
    const Vec3d a(na), r(nr);  // atan2 of |a x r| and a.r: accurate for tiny angles, unlike acos
    s.angle_deg.push_back(std::atan2(length(cross(a, r)), dot(a, r)) * 180.0 / kPi);
  }
  return s;
}

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const size_t k = percentile_index(v.size(), p);
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

}  // namespace

size_t percentile_index(size_t n, double p) { return std::min(n - 1, size_t(p * double(n - 1) + 0.5)); }

ErrorStats summarize(ErrorSamples& samples) {
  ErrorStats s;
  s.rays = samples.t_rel.size();
  if (samples.t_rel.empty()) return s;
  s.t_max = *std::max_element(samples.t_rel.begin(), samples.t_rel.end());
  s.angle_max = *std::max_element(samples.angle_deg.begin(), samples.angle_deg.end());
  s.t_p50 = percentile(samples.t_rel, 0.50);
  s.t_p99 = percentile(samples.t_rel, 0.99);
  s.angle_p99 = percentile(samples.angle_deg, 0.99);
  return s;
}

DiffResult diff_hits(const Scene& scene, std::span<const Ray> rays, std::span<const Hit> a, std::span<const Hit> b,
                     std::span<const ReferenceHit> ref, const DiffOptions& o) {
  RP_CHECK(a.size() == rays.size() && b.size() == rays.size(), "diff: ", rays.size(), " rays but ", a.size(), " and ",
           b.size(), " hits");
  RP_CHECK(ref.empty() || ref.size() == rays.size(), "diff: ", rays.size(), " rays but ", ref.size(),
           " reference hits");
  DiffResult d;
  d.rays = rays.size();
  d.has_reference = !ref.empty();
  d.per_ray.resize(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const DiffClass c = classify(a[i], b[i], o);
    d.per_ray[i] = c;
    ++d.count[size_t(c)];
    if (!d.has_reference) continue;
    const bool sa = supported(a[i], ref[i], o), sb = supported(b[i], ref[i], o);
    Support& s = d.support[size_t(c)];
    (sa && sb ? s.both : sa ? s.a : sb ? s.b : s.neither) += 1;
  }
  if (d.has_reference) {
    d.a_samples = error_samples(scene, rays, a, ref);
    d.b_samples = error_samples(scene, rays, b, ref);
    d.a_vs_reference = summarize(d.a_samples);
    d.b_vs_reference = summarize(d.b_samples);
  }
  return d;
}

std::string format_table(const DiffResult& d, const std::string& a, const std::string& b) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof line, "%zu rays, %s (A) vs %s (B): agreement %.5f%% (agree + tie)\n\n", d.rays,
                a.c_str(), b.c_str(), 100.0 * d.agreement());
  s << line;
  if (d.has_reference) {
    std::snprintf(line, sizeof line, "%-16s %10s %10s   %s\n", "class", "rays", "rate", "reference supports: A / B / both / neither");
  } else {
    std::snprintf(line, sizeof line, "%-16s %10s %10s\n", "class", "rays", "rate");
  }
  s << line;
  for (int c = 0; c < kDiffClasses; ++c) {
    const double rate = d.rays ? 100.0 * double(d.count[size_t(c)]) / double(d.rays) : 0.0;
    std::snprintf(line, sizeof line, "%-16s %10zu %9.5f%%", to_string(DiffClass(c)), d.count[size_t(c)], rate);
    s << line;
    if (d.has_reference && c != int(DiffClass::agree)) {
      const Support& p = d.support[size_t(c)];
      std::snprintf(line, sizeof line, "   %zu / %zu / %zu / %zu", p.a, p.b, p.both, p.neither);
      s << line;
    }
    s << '\n';
  }
  if (d.has_reference) {
    s << "\nagainst the reference (rays where the backend hits the reference's primitive):\n";
    std::snprintf(line, sizeof line, "%-16s %10s %12s %12s %12s %14s %14s\n", "backend", "rays", "t err p50", "t err p99",
                  "t err max", "normal p99 deg", "normal max deg");
    s << line;
    for (const auto& [name, e] : {std::pair{a, d.a_vs_reference}, std::pair{b, d.b_vs_reference}}) {
      std::snprintf(line, sizeof line, "%-16s %10zu %12.3g %12.3g %12.3g %14.3g %14.3g\n", name.c_str(), e.rays, e.t_p50,
                    e.t_p99, e.t_max, e.angle_p99, e.angle_max);
      s << line;
    }
  }
  return s.str();
}

std::string to_json(const DiffResult& d, const std::string& scene, const std::string& rays, const std::string& a,
                    const std::string& b, const DiffOptions& o) {
  nlohmann::json j;
  j["scene"] = scene;
  j["rays"] = rays;
  j["count"] = d.rays;
  j["a"] = a;
  j["b"] = b;
  j["tie_tolerance"] = o.tie_tolerance;
  j["t_tolerance"] = o.t_tolerance;
  j["agreement"] = d.agreement();
  for (int c = 0; c < kDiffClasses; ++c) {
    nlohmann::json e;
    e["count"] = d.count[size_t(c)];
    e["rate"] = d.rays ? double(d.count[size_t(c)]) / double(d.rays) : 0.0;
    if (d.has_reference) {
      const Support& p = d.support[size_t(c)];
      e["reference_supports"] = {{"a", p.a}, {"b", p.b}, {"both", p.both}, {"neither", p.neither}};
    }
    j["classes"][to_string(DiffClass(c))] = e;
  }
  if (d.has_reference) {
    for (const auto& [key, e] : {std::pair{"a_vs_reference", d.a_vs_reference}, std::pair{"b_vs_reference", d.b_vs_reference}})
      j[key] = {{"rays", e.rays},         {"t_rel_error_p50", e.t_p50}, {"t_rel_error_p99", e.t_p99},
                {"t_rel_error_max", e.t_max}, {"normal_angle_p99_deg", e.angle_p99}, {"normal_angle_max_deg", e.angle_max}};
  }
  return j.dump(2) + "\n";
}

Image mismatch_image(const DiffResult& d, const RaySet& set, std::span<const Hit> hits_a) {
  RP_CHECK(set.width > 0 && set.height > 0 && set.pixel.size() == d.per_ray.size(),
           "diff: a mismatch image needs camera rays (--rays primary or diffuse)");
  Image img;
  img.width = set.width;
  img.height = set.height;
  img.rgb.assign(size_t(set.width) * size_t(set.height) * 3, 0.0f);
  static constexpr float kColour[kDiffClasses][3] = {
      {0.05f, 0.05f, 0.05f}, {1.0f, 0.9f, 0.0f}, {1.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 1.0f}, {1.0f, 0.5f, 0.0f}};
  // Agreeing hits first, then every other class as a 3x3 mark so a single ray shows.
  for (size_t i = 0; i < d.per_ray.size(); ++i)
    if (d.per_ray[i] == DiffClass::agree && hits_a[i].hit())
      for (int k = 0; k < 3; ++k) img.rgb[size_t(set.pixel[i]) * 3 + size_t(k)] = kColour[0][k];
  for (size_t i = 0; i < d.per_ray.size(); ++i) {
    if (d.per_ray[i] == DiffClass::agree) continue;
    const int x = int(set.pixel[i] % uint32_t(set.width)), y = int(set.pixel[i] / uint32_t(set.width));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int px = x + dx, py = y + dy;
        if (px < 0 || py < 0 || px >= set.width || py >= set.height) continue;
        for (int k = 0; k < 3; ++k)
          img.rgb[(size_t(py) * size_t(set.width) + size_t(px)) * 3 + size_t(k)] = kColour[size_t(d.per_ray[i])][k];
      }
  }
  return img;
}

}  // namespace rp
