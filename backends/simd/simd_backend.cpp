#include "backends/simd/simd_backend.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/large_packet.h"
#include "backends/simd/point_query.h"
#include "backends/simd/stream.h"
#include "backends/simd/traversal.h"
#include "backends/simd/watertight.h"
#include "base/error.h"

namespace rp::bvh8 {

namespace {

/// The trees of a scene's instanced meshes (build_mesh), each once, and the instance tree
/// over its instances (build_instances): the second and top levels (levels.h).
struct InstanceTrees {
  std::vector<Bvh8> meshes;  ///< one per instanced mesh that some instance places
  std::vector<uint64_t> uid;      ///< Scene::mesh_uid of meshes[k]
  std::vector<uint64_t> version;  ///< the Scene::mesh_version that meshes[k] holds
  std::vector<uint32_t> base;     ///< the Scene::mesh_base that meshes[k]'s prim_ids start at
  std::vector<float> leaf_size;   ///< mean_leaf_size of meshes[k]
  std::vector<Placed> placed;  ///< instance i of the scene: placed[i]
  InstanceTree tree;
  size_t mesh_bytes = 0;
  double seconds = 0;

  InstanceTrees(const Scene& scene, const BuildOptions& options) {
    UpdateReport ignored;
    update(scene, options, 0.0, ignored);
  }

  /// Brings the trees to the scene's instances: a mesh's tree kept while the mesh (by its uid)
  /// is placed, refit when its vertices changed (rebuilt past `limit`, see refit), built for a
  /// mesh placed anew; the placements and the instance tree made again.
  void update(const Scene& scene, const BuildOptions& options, double limit, UpdateReport& report) {
    const auto start = std::chrono::steady_clock::now();
    std::unordered_map<uint64_t, uint32_t> had;
    for (uint32_t k = 0; k < meshes.size(); ++k) had.emplace(uid[k], k);
    std::vector<Bvh8> next;
    std::vector<uint64_t> next_uid, next_version;
    std::vector<uint32_t> next_base;
    std::vector<float> next_leaf_size;
    std::vector<uint32_t> tree_of(scene.meshes().size(), kInvalidId);
    for (const Instance& in : scene.instances()) {
      if (tree_of[in.mesh] != kInvalidId) continue;
      tree_of[in.mesh] = uint32_t(next.size());
      const uint64_t u = scene.mesh_uid(in.mesh), v = scene.mesh_version(in.mesh);
      const auto old = had.find(u);
      if (old == had.end()) {
        next.push_back(build_mesh(scene, in.mesh, options));
        next_leaf_size.push_back(mean_leaf_size(next.back()));
        ++report.rebuilds;
      } else {
        Bvh8& t = meshes[old->second];
        float size = leaf_size[old->second];
        renumber(t, base[old->second], scene.mesh_base(in.mesh));
        if (version[old->second] != v) {
          if (refit(t, scene, in.mesh, limit) == Refit::done) {
            ++report.refits;
          } else {
            t = build_mesh(scene, in.mesh, options);
            ++report.rebuilds;
          }
          size = mean_leaf_size(t);
        }
        next.push_back(std::move(t));
        next_leaf_size.push_back(size);
      }
      next_uid.push_back(u);
      next_version.push_back(v);
      next_base.push_back(scene.mesh_base(in.mesh));
    }
    meshes = std::move(next);
    uid = std::move(next_uid);
    version = std::move(next_version);
    base = std::move(next_base);
    leaf_size = std::move(next_leaf_size);
    mesh_bytes = 0;
    for (const Bvh8& m : meshes) mesh_bytes += m.stats.bytes;
    placed.clear();  // meshes is complete: the instances point into it
    for (const Instance& in : scene.instances()) {
      const float scale = float(std::cbrt(std::abs(double(in.object_to_world.determinant()))));
      const uint32_t k = tree_of[in.mesh];
      placed.push_back({in.world_to_object, &meshes[k], leaf_size[k] * scale});
    }
    tree = build_instances(scene);
    report.top = true;
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

/// The traversals of one state of the trees (they keep references into them).
template <class Kernel>
struct Tracers {
  Traversal<Kernel> traversal;
  LargePacketTraversal<Kernel> large;
  StreamTraversal<Kernel> stream;

  Tracers(const Bvh8& world, const Scene& scene, const InstanceTrees& level)
      : traversal(world, scene, level.tree, level.placed), large(traversal), stream(traversal) {}
};

template <class Kernel>
class SimdBackend final : public Backend {
 public:
  SimdBackend(const Scene& scene, const std::string& variant, const BuildOptions& build_options,
              const BackendOptions& options, bool large_packets, bool streams)
      : Backend(scene),
        bvh_(build(scene, build_options)),
        level_(scene, build_options),
        build_options_(build_options),
        refit_limit_(options.refit_limit),
        large_packets_(large_packets),
        streams_(streams) {
    tracers_.emplace(bvh_, scene, level_);
    info_.name = "simd";
    info_.variant = variant;
    info_.build_seconds = bvh_.stats.seconds + level_.seconds;
    describe();
  }

  const BackendInfo& info() const noexcept override { return info_; }

 private:
  void trace_closest(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    const Tracers<Kernel>& t = *tracers_;
    if (coherence == Coherence::incoherent) {
      if (streams_) {
        t.stream.intersect(rays, hits);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = t.traversal.intersect_single(rays[i]);
      }
    } else if (large_packets_) {
      t.large.intersect(rays, hits);
    } else {
      for (size_t base = 0; base < rays.size(); base += 8)
        t.traversal.intersect_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), hits.subspan(base));
    }
  }

  void trace_any(std::span<const Ray> rays, std::span<uint8_t> out, Coherence coherence) const noexcept override {
    const Tracers<Kernel>& t = *tracers_;
    if (coherence == Coherence::incoherent) {
      if (streams_) {
        t.stream.occluded(rays, out);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) out[i] = valid_ray(rays[i]) && t.traversal.occluded_single(rays[i]);
      }
    } else if (large_packets_) {
      t.large.occluded(rays, out);
    } else {
      for (size_t base = 0; base < rays.size(); base += 8)
        t.traversal.occluded_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), out.subspan(base));
    }
  }

  void trace_closest_filtered(std::span<const Ray> rays, std::span<Hit> hits,
                              const TraceOptions& options) const override {
    for (size_t i = 0; i < rays.size(); ++i) {
      hits[i] = Hit{};
      if (!valid_ray(rays[i])) continue;
      const HitGate g = gate(options, rays[i], i);
      GatedClosest<Kernel, HitGate> q(rays[i], g);
      tracers_->traversal.single(rays[i], q);
      hits[i] = q.best;
    }
  }

  void trace_any_filtered(std::span<const Ray> rays, std::span<uint8_t> out,
                          const TraceOptions& options) const override {
    for (size_t i = 0; i < rays.size(); ++i) {
      out[i] = 0;
      if (!valid_ray(rays[i])) continue;
      const HitGate g = gate(options, rays[i], i);
      GatedAny<Kernel, HitGate> q(rays[i], g);
      tracers_->traversal.single(rays[i], q);
      out[i] = uint8_t(q.found);
    }
  }

  void trace_every(std::span<const Ray> rays, size_t index, const TraceOptions& options,
                   std::vector<Hit>& out) const override {
    const HitGate g = gate(options, rays[index], index);
    Every<Kernel, HitGate> q(rays[index], g, out);
    tracers_->traversal.single(rays[index], q);
  }

  void closest_points_of(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const override {
    for (size_t i = 0; i < queries.size(); ++i) {
      out[i] = ClosestPoint{};
      if (!valid_point_query(queries[i])) continue;
      PointSearch s(queries[i]);
      closest_point(bvh_, level_.tree, level_.placed, scene(), s);
      out[i] = s.best;
    }
  }

  /// The world's tree rebuilt when the layout changed, refit when only a world mesh's
  /// vertices did; the instance level brought up to date when any instance changed.
  UpdateReport apply_changes(uint64_t since) override {
    const Scene& s = scene();
    UpdateReport r;
    tracers_.reset();  // they point into the trees
    bool world_moved = s.layout_version() > since;
    for (uint32_t m = 0; m < s.meshes().size() && !world_moved; ++m)
      world_moved = !s.is_instanced(m) && s.mesh_version(m) > since;
    if (s.layout_version() <= since && world_moved && refit(bvh_, s, kInvalidId, refit_limit_) == Refit::done) {
      ++r.refits;
    } else if (world_moved) {
      bvh_ = build(s, build_options_);
      ++r.rebuilds;
    }
    if (s.instances_version() > since) level_.update(s, build_options_, refit_limit_, r);
    tracers_.emplace(bvh_, s, level_);
    describe();
    return r;
  }

  /// The info's bytes and figures of the trees as they are.
  void describe() {
    info_.levels = {bvh_.stats.bytes + level_.tree.stats.bytes, level_.mesh_bytes};
    info_.bytes = info_.levels.top + info_.levels.meshes;
    info_.stats = {{"nodes", double(bvh_.stats.nodes)},
                   {"leaves", double(bvh_.stats.leaves)},
                   {"depth", double(bvh_.stats.depth)},
                   {"sah_cost", bvh_.stats.sah_cost},
                   {"prims", double(bvh_.stats.prims)}};
    if (scene().instances().empty()) return;
    size_t mesh_prims = 0, mesh_nodes = 0, mesh_leaves = 0;
    uint32_t mesh_depth = 0;
    for (const Bvh8& m : level_.meshes) {
      mesh_prims += m.stats.prims;
      mesh_nodes += m.stats.nodes;
      mesh_leaves += m.stats.leaves;
      mesh_depth = std::max(mesh_depth, m.stats.depth);
    }
    info_.stats.insert(info_.stats.end(), {{"instances", double(level_.tree.stats.prims)},
                                           {"instance_nodes", double(level_.tree.stats.nodes)},
                                           {"instance_depth", double(level_.tree.stats.depth)},
                                           {"world_bytes", double(bvh_.stats.bytes)},
                                           {"instance_bytes", double(level_.tree.stats.bytes)},
                                           {"mesh_trees", double(level_.meshes.size())},
                                           {"mesh_prims", double(mesh_prims)},
                                           {"mesh_nodes", double(mesh_nodes)},
                                           {"mesh_leaves", double(mesh_leaves)},
                                           {"mesh_depth", double(mesh_depth)}});
  }

  Bvh8 bvh_;
  InstanceTrees level_;
  std::optional<Tracers<Kernel>> tracers_;  ///< over bvh_ and level_; remade by every update
  BuildOptions build_options_;
  double refit_limit_;
  bool large_packets_;
  bool streams_;  ///< incoherent batches as ray streams (else ray by ray)
  BackendInfo info_;
};

/// The coherent method of `options`: large packets (the default) or independent 8-ray packets.
bool large_packets(const BackendOptions& options) {
  const std::string& m = options.coherent_method;
  if (m.empty() || m == "large") return true;
  if (m == "packet8") return false;
  throw Error(cat("simd: unknown coherent method '", m, "' (large, packet8)"));
}

/// The incoherent method of `options`: ray streams (the default) or single rays.
bool streams(const BackendOptions& options) {
  const std::string& m = options.incoherent_method;
  if (m.empty() || m == "stream") return true;
  if (m == "single") return false;
  throw Error(cat("simd: unknown incoherent method '", m, "' (stream, single)"));
}

}  // namespace

std::vector<std::string> variants() { return {"default", "median", "watertight", "spatial"}; }

std::vector<std::string> coherent_methods() { return {"large", "packet8"}; }

std::vector<std::string> incoherent_methods() { return {"stream", "single"}; }

std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options) {
  const std::string& v = options.variant;
  RP_CHECK(options.refit_limit >= 1.0, "simd: refit limit ", options.refit_limit, " must be at least 1");
  const bool large = large_packets(options), stream = streams(options);
  if (v == "default") return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{}, options, large, stream);
  if (v == "median")
    return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{.rule = SplitRule::median}, options, large,
                                                   stream);
  if (v == "watertight")
    return std::make_unique<SimdBackend<WatertightKernel>>(scene, v, BuildOptions{}, options, large, stream);
  if (v == "spatial")
    return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{.spatial_splits = true}, options, large,
                                                   stream);
  throw Error(cat("simd: unknown variant '", v, "' (default, median, watertight, spatial)"));
}

}  // namespace rp::bvh8
