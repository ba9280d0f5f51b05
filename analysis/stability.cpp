#include "analysis/stability.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>

#include "analysis/reference.h"
#include "analysis/stability/family.h"
#include "analysis/stability/judge.h"
#include "base/error.h"
#include "core/scene_transform.h"

namespace rp::stability {

namespace {

uint64_t fnv1a(const std::string& s, uint64_t seed) {
  uint64_t h = 1469598103934665603ull ^ seed;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string pow10_label(int k) { return "1e" + std::to_string(k); }

}  // namespace

std::vector<std::pair<std::string, std::string>> family_names() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const FamilySpec& f : family_table()) out.emplace_back(f.name, f.description);
  return out;
}

std::vector<std::string> scalar_methods() { return scalar_method_names(); }

std::vector<Result> run(const Scene& base, const Options& o) {
  RP_CHECK(o.make_backend, "stability: no backend factory");
  RP_CHECK(o.rays >= 1 && o.rays <= 1u << 22, "stability: rays per family ", o.rays, " is out of range (1..4194304)");
  const std::vector<FamilySpec>& table = family_table();
  for (const std::string& name : o.families)
    RP_CHECK(std::any_of(table.begin(), table.end(), [&](const FamilySpec& f) { return f.name == name; }),
             "stability: unknown family '", name, "'");
  auto wanted = [&](const FamilySpec& f) {
    return o.families.empty() || std::find(o.families.begin(), o.families.end(), f.name) != o.families.end();
  };
  std::vector<Result> out;
  const uint32_t n = o.rays;
  const Topology topology(base);

  // One scene at a time: its reference and backends are built once for all its families, which
  // are generated (in table order) and judged there.
  auto scene_group = [&](std::shared_ptr<const Scene> scene, const Geom& geom, const Reference& reference,
                         const std::vector<const FamilySpec*>& specs,
                         const std::function<std::string(const FamilySpec&)>& param_of, int exponent,
                         bool has_exponent, std::mt19937_64* own_rng) {
    const Context context{geom, topology, reference};
    std::map<std::string, MethodBackend> backends;
    for (const FamilySpec* spec : specs) {
      const std::string param = param_of(*spec);
      Family f;
      f.name = spec->name;
      f.param = param;
      f.exponent = exponent;
      f.has_exponent = has_exponent;
      f.scene = scene;
      f.diagonal = scene_diagonal(*scene);
      std::mt19937_64 rng(fnv1a(std::string(spec->seed_key ? spec->seed_key : spec->name) + param, o.seed));
      spec->generate(f, context, n, own_rng ? *own_rng : rng);
      if (f.rays.empty()) continue;
      if (o.progress) o.progress(f.name + (f.param.empty() ? "" : " " + f.param));
      evaluate(f, reference, o, backends, out);
    }
  };
  const auto no_param = [](const FamilySpec&) { return std::string(); };
  auto specs_where = [&](std::initializer_list<Where> where) {
    std::vector<const FamilySpec*> specs;
    for (const FamilySpec& f : table)
      if (wanted(f) && std::find(where.begin(), where.end(), f.where) != where.end()) specs.push_back(&f);
    return specs;
  };

  // The given scene's families.
  if (const auto specs = specs_where({Where::given}); !specs.empty()) {
    auto scene = std::make_shared<const Scene>(base);
    scene_group(scene, Geom{&base}, Reference(*scene), specs, no_param, 0, false, nullptr);
  }
  // Families with a scene of their own, one scene each, built from the family's random stream,
  // which its rays then continue.
  for (const FamilySpec* spec : specs_where({Where::own})) {
    std::mt19937_64 rng(fnv1a(spec->name, o.seed));
    auto scene = std::shared_ptr<const Scene>(spec->scene(rng));
    scene_group(scene, Geom{scene.get()}, Reference(*scene), {spec}, no_param, 0, false, &rng);
  }
  // Moved and scaled copies of the given scene. Translation is along a fixed, non-axis
  // direction so every coordinate is large.
  struct Copy {
    Where where;
    int k;
  };
  std::vector<Copy> copies;
  for (int k = 0; k <= 7; ++k) copies.push_back({Where::translated, k});
  for (int k : {-6, -3, 3, 6}) copies.push_back({Where::scaled, k});
  for (const Copy& copy : copies) {
    const auto specs = specs_where({copy.where, Where::moved});
    if (specs.empty()) continue;
    const bool moved = copy.where == Where::translated;
    const double p = std::pow(10.0, copy.k);
    const Vec3d offset = moved ? Vec3d{p, 0.75 * p, 0.5 * p} : Vec3d(0.0);
    const double scale = moved ? 1.0 : p;
    auto scene = std::make_shared<const Scene>(transformed(base, scale, offset));
    const Reference reference(*scene);
    // The translated and scaled families are named by 1e<k>; the leaving ones by the copy.
    const auto param_of = [&](const FamilySpec& spec) {
      return spec.where == Where::moved ? std::string(moved ? "translated " : "scaled ") + pow10_label(copy.k)
                                        : pow10_label(copy.k);
    };
    scene_group(scene, Geom{&base, scale, offset}, reference, specs, param_of, copy.k, true, nullptr);
  }
  return out;
}

}  // namespace rp::stability
