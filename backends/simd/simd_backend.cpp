#include "backends/simd/simd_backend.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "backends/simd/bvh8.h"
#include "backends/simd/large_packet.h"
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
  std::vector<Placed> placed;  ///< instance i of the scene: placed[i]
  InstanceTree tree;
  size_t mesh_bytes = 0;
  double seconds = 0;

  InstanceTrees(const Scene& scene, const BuildOptions& options) {
    if (scene.instances().empty()) return;
    const auto start = std::chrono::steady_clock::now();
    std::vector<uint32_t> tree_of(scene.meshes().size(), kInvalidId);
    for (const Instance& in : scene.instances())
      if (tree_of[in.mesh] == kInvalidId) {
        tree_of[in.mesh] = uint32_t(meshes.size());
        meshes.push_back(build_mesh(scene, in.mesh, options));
        mesh_bytes += meshes.back().stats.bytes;
      }
    std::vector<float> leaf_size;  // meshes is complete: the instances point into it
    for (const Bvh8& m : meshes) leaf_size.push_back(mean_leaf_size(m));
    for (const Instance& in : scene.instances()) {
      const float scale = float(std::cbrt(std::abs(double(in.object_to_world.determinant()))));
      const uint32_t k = tree_of[in.mesh];
      placed.push_back({in.world_to_object, &meshes[k], leaf_size[k] * scale});
    }
    tree = build_instances(scene);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

template <class Kernel>
class SimdBackend final : public Backend {
 public:
  SimdBackend(const Scene& scene, const std::string& variant, const BuildOptions& build_options, bool large_packets,
              bool streams)
      : bvh_(build(scene, build_options)),
        level_(scene, build_options),
        traversal_(bvh_, scene, level_.tree, level_.placed),
        large_(traversal_),
        stream_(traversal_),
        large_packets_(large_packets),
        streams_(streams) {
    info_.name = "simd";
    info_.variant = variant;
    info_.build_seconds = bvh_.stats.seconds + level_.seconds;
    info_.levels = {bvh_.stats.bytes + level_.tree.stats.bytes, level_.mesh_bytes};
    info_.bytes = info_.levels.top + info_.levels.meshes;
    info_.stats = {{"nodes", double(bvh_.stats.nodes)},  {"leaves", double(bvh_.stats.leaves)},
                   {"depth", double(bvh_.stats.depth)},  {"sah_cost", bvh_.stats.sah_cost},
                   {"prims", double(bvh_.stats.prims)}};
    if (!scene.instances().empty()) {
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
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    if (coherence == Coherence::incoherent) {
      if (streams_) {
        stream_.intersect(rays, hits);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = traversal_.intersect_single(rays[i]);
      }
    } else if (large_packets_) {
      large_.intersect(rays, hits);
    } else {
      for (size_t base = 0; base < rays.size(); base += 8)
        traversal_.intersect_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), hits.subspan(base));
    }
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> out, Coherence coherence) const noexcept override {
    if (coherence == Coherence::incoherent) {
      if (streams_) {
        stream_.occluded(rays, out);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) out[i] = valid_ray(rays[i]) && traversal_.occluded_single(rays[i]);
      }
    } else if (large_packets_) {
      large_.occluded(rays, out);
    } else {
      for (size_t base = 0; base < rays.size(); base += 8)
        traversal_.occluded_packet(rays.subspan(base, std::min<size_t>(8, rays.size() - base)), out.subspan(base));
    }
  }

  const BackendInfo& info() const noexcept override { return info_; }

 private:
  Bvh8 bvh_;
  InstanceTrees level_;
  Traversal<Kernel> traversal_;
  LargePacketTraversal<Kernel> large_;
  StreamTraversal<Kernel> stream_;
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
  const bool large = large_packets(options), stream = streams(options);
  if (v == "default") return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{}, large, stream);
  if (v == "median")
    return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{.rule = SplitRule::median}, large, stream);
  if (v == "watertight")
    return std::make_unique<SimdBackend<WatertightKernel>>(scene, v, BuildOptions{}, large, stream);
  if (v == "spatial")
    return std::make_unique<SimdBackend<MtKernel>>(scene, v, BuildOptions{.spatial_splits = true}, large, stream);
  throw Error(cat("simd: unknown variant '", v, "' (default, median, watertight, spatial)"));
}

}  // namespace rp::bvh8
