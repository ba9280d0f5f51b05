#include "backends/embree/embree_backend.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <mutex>

#include "backends/embree/embree_callbacks.h"
#include "backends/embree/embree_device.h"
#include "base/error.h"
#include "simd/flush_denormals.h"

namespace rp::embree {

namespace {

using namespace detail;

/// True when Embree reads mesh m's positions where they are: it loads 16 bytes at each
/// vertex, which a stride of 16 bytes or more leaves inside the vertex's own record (a shared
/// mesh's caller promises that much of its last record, Scene::add_shared_mesh). The scene's
/// own positions (12 bytes apart) and narrower shared ones are copied into a padded buffer.
bool shares_positions(const MeshView& m) { return m.positions.stride() >= 16; }

class EmbreeBackend final : public Backend {
 public:
  EmbreeBackend(const Scene& scene, const BackendOptions& options)
      : Backend(scene),
        scene_(scene),
        user_{&scene},
        method_(parse_method(options.coherent_method)),
        incoherent_stream_(parse_incoherent(options.incoherent_method)) {
    const auto start = std::chrono::steady_clock::now();
    info_.name = "embree";
    info_.variant = options.variant;
    if (options.variant == "robust")
      flags_ = RTC_SCENE_FLAG_ROBUST;
    else if (options.variant == "compact")
      flags_ = RTC_SCENE_FLAG_COMPACT;
    else if (options.variant == "high")
      quality_ = RTC_BUILD_QUALITY_HIGH;
    else if (options.variant == "dynamic") {
      flags_ = RTC_SCENE_FLAG_DYNAMIC;
      quality_ = RTC_BUILD_QUALITY_LOW;
      geometry_quality_ = RTC_BUILD_QUALITY_REFIT;
    } else if (options.variant != "default")
      throw Error(cat("embree: unknown variant '", options.variant, "' (default, robust, compact, high, dynamic)"));
    device_ = &device_for(options.device_config);
    build();
    info_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  ~EmbreeBackend() override { release(); }

  const BackendInfo& info() const noexcept override { return info_; }

 private:
  /// Where mesh m's triangle geometry is: the top scene's geometry `id`, or its child scene's
  /// (an instanced mesh); no scene for a mesh without one (no triangles, or not placed).
  struct MeshGeometry {
    RTCScene scene = nullptr;
    unsigned id = RTC_INVALID_GEOMETRY_ID;
  };

  /// Builds the Embree scenes over the scene as it is, releasing any built before.
  void build() {
    release();
    const Scene& scene = scene_;
    RTCDevice dev = device_->handle;
    // Embree's memory monitor is per device: serialise builds so the delta is this scene's.
    static std::mutex build_mutex;
    std::lock_guard lock(build_mutex);
    const int64_t bytes_before = device_->bytes.load();
    size_t buffer_bytes = 0;

    scene_handle_ = rtcNewScene(dev);
    check(dev, "embree: rtcNewScene");
    rtcSetSceneFlags(scene_handle_, scene_flags());
    rtcSetSceneBuildQuality(scene_handle_, quality_);

    triangle_data_.clear();
    triangle_data_.reserve(scene.meshes().size());  // never reallocated: Embree keeps pointers
    mesh_geometry_.assign(scene.meshes().size(), {});
    geom_base_.clear();
    // The instanced meshes first, each a child scene of its own, built once (the mesh level).
    for (const Instance& in : scene.instances()) {
      if (mesh_geometry_[in.mesh].scene || scene.meshes()[in.mesh].triangle_count() == 0) continue;
      RTCScene c = rtcNewScene(dev);
      check(dev, "embree: rtcNewScene");
      children_.push_back(c);
      rtcSetSceneFlags(c, scene_flags());
      rtcSetSceneBuildQuality(c, quality_);
      RTCGeometry g = triangle_geometry(dev, in.mesh, buffer_bytes);
      rtcCommitGeometry(g);
      mesh_geometry_[in.mesh] = {c, rtcAttachGeometry(c, g)};
      rtcReleaseGeometry(g);
      check(dev, "embree: attach geometry");
    }
    for (RTCScene c : children_) rtcCommitScene(c);
    check(dev, "embree: rtcCommitScene (an instanced mesh)");
    const int64_t mesh_delta = device_->bytes.load() - bytes_before;
    info_.levels.meshes = mesh_delta > int64_t(buffer_bytes) ? size_t(mesh_delta) - buffer_bytes : 0;
    const int64_t top_before = device_->bytes.load();
    const size_t mesh_buffers = buffer_bytes;

    for (size_t m = 0; m < scene.meshes().size(); ++m) {
      if (scene.is_instanced(m) || scene.meshes()[m].triangle_count() == 0) continue;
      mesh_geometry_[m] = {scene_handle_,
                           attach(triangle_geometry(dev, uint32_t(m), buffer_bytes), scene.mesh_base(m))};
    }
    add_user<SphereKind>(dev);
    add_user<QuadricKind>(dev);
    add_user<PolygonKind>(dev);
    // Then one instance geometry per instance, at consecutive ids from first_instance_geom_.
    first_instance_geom_ = uint32_t(geom_base_.size());
    for (TriangleData& d : triangle_data_)
      if (d.first_instance_geom != kNoInstance) d.first_instance_geom = first_instance_geom_;
    instance_meshes_.clear();
    for (uint32_t i = 0; i < scene.instances().size(); ++i) {
      const Instance& in = scene.instances()[i];
      instance_meshes_.push_back(scene.mesh_uid(in.mesh));
      if (!mesh_geometry_[in.mesh].scene) continue;  // a mesh without triangles
      RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(g, mesh_geometry_[in.mesh].scene);
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, &in.object_to_world.m[0][0]);
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(scene_handle_, g, first_instance_geom_ + i);
      rtcReleaseGeometry(g);
      check(dev, "embree: instance geometry");
    }

    rtcCommitScene(scene_handle_);
    check(dev, "embree: rtcCommitScene");
    coherent_occlusion_ = scene.instances().empty();
    const int64_t top_delta = device_->bytes.load() - top_before;
    const int64_t top_buffers = int64_t(buffer_bytes - mesh_buffers);
    info_.levels.top = top_delta > top_buffers ? size_t(top_delta - top_buffers) : 0;
    info_.bytes = info_.levels.top + info_.levels.meshes;
  }

  void release() {
    if (scene_handle_) rtcReleaseScene(scene_handle_);
    scene_handle_ = nullptr;
    for (RTCScene c : children_) rtcReleaseScene(c);
    children_.clear();
  }

  /// Moved vertices: their meshes' vertex buffers rewritten and committed (Embree refits the
  /// "dynamic" variant's trees and rebuilds the others'); moved instances: their transforms.
  /// Anything added or removed: every scene built again.
  UpdateReport apply_changes(uint64_t since) override {
    const Scene& s = scene_;
    UpdateReport r;
    std::vector<uint64_t> uids;
    for (const Instance& in : s.instances()) uids.push_back(s.mesh_uid(in.mesh));
    if (s.layout_version() > since || uids != instance_meshes_) {
      build();
      r.rebuilds = 1;
      r.top = !s.instances().empty();
      return r;
    }
    RTCDevice dev = device_->handle;
    std::vector<RTCScene> children;
    bool top = false;
    for (uint32_t m = 0; m < s.meshes().size(); ++m) {
      const MeshGeometry& mg = mesh_geometry_[m];
      if (s.mesh_version(m) <= since || !mg.scene) continue;
      RTCGeometry g = rtcGetGeometry(mg.scene, mg.id);
      if (!shares_positions(s.meshes()[m])) {
        auto* v = static_cast<Vec3f*>(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, 0));
        check(dev, "embree: vertex buffer");
        std::copy(s.meshes()[m].positions.begin(), s.meshes()[m].positions.end(), v);
      }
      rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
      rtcCommitGeometry(g);
      check(dev, "embree: vertex update");
      if (mg.scene == scene_handle_)
        top = true;
      else
        children.push_back(mg.scene);
      ++(geometry_quality_ == RTC_BUILD_QUALITY_REFIT ? r.refits : r.rebuilds);
    }
    for (RTCScene c : children) rtcCommitScene(c);
    check(dev, "embree: rtcCommitScene (an instanced mesh)");
    if (s.instances_version() > since) {
      for (uint32_t i = 0; i < s.instances().size(); ++i) {
        if (!mesh_geometry_[s.instances()[i].mesh].scene) continue;
        RTCGeometry g = rtcGetGeometry(scene_handle_, first_instance_geom_ + i);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, &s.instances()[i].object_to_world.m[0][0]);
        rtcCommitGeometry(g);
      }
      check(dev, "embree: instance transforms");
      top = r.top = true;
    }
    if (top || !children.empty()) {
      rtcCommitScene(scene_handle_);
      check(dev, "embree: rtcCommitScene");
    }
    return r;
  }

  void trace_closest(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    simd::FlushDenormals ftz;
    QueryContext q = context(rays, coherence);
    if (coherence == Coherence::incoherent && incoherent_stream_) {
      intersect_stream(q, hits);
      return;
    }
    if (coherence == Coherence::incoherent) {
      for (size_t i = 0; i < rays.size(); ++i) {
        if (valid_ray(rays[i])) intersect1(q, i, hits[i]);
        else put_miss(hits[i]);
      }
      return;
    }
    switch (method_) {
      case Method::packet8: intersect_packets<RTCRayHit8, 8>(q, hits); break;
      case Method::packet16: intersect_packets<RTCRayHit16, 16>(q, hits); break;
      case Method::stream: intersect_stream(q, hits); break;
    }
  }

  void trace_any(std::span<const Ray> rays, std::span<uint8_t> out, Coherence coherence) const noexcept override {
    simd::FlushDenormals ftz;
    // Embree 3.13.5's coherent any-hit traversal (rtcOccluded16, and rtcOccluded1M, which
    // uses it) never returns on some rays of a scene with instances (reproduced with Embree
    // alone: one instance of a triangle mesh, two one-primitive user geometries, 16 rays; and
    // with no user geometry: `raypack bench --scene bench/scenes/bunnies-instanced.json
    // --method 'embree (stream|rtcIntersect16)'` hung in rtcOccluded16 on every run); every
    // scene with instances sends its occlusion rays without the coherent flag.
    QueryContext q = context(rays, coherent_occlusion_ ? coherence : Coherence::incoherent);
    if (coherence == Coherence::incoherent && incoherent_stream_) {
      occluded_stream(q, out);
      return;
    }
    if (coherence == Coherence::incoherent) {
      for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        if (!valid_ray(r)) { out[i] = 0; continue; }
        if (hits_plane(r)) { out[i] = 1; continue; }
        RTCRay ray = to_embree(r, i);
        rtcOccluded1(scene_handle_, &q.embree, &ray);
        out[i] = uint8_t(ray.tfar < 0.0f);
      }
      return;
    }
    switch (method_) {
      case Method::packet8: occluded_packets<RTCRay8, 8>(q, out); break;
      case Method::packet16: occluded_packets<RTCRay16, 16>(q, out); break;
      case Method::stream: occluded_stream(q, out); break;
    }
  }

  static constexpr Ray kDummy{{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 0.0f};
  static constexpr Ray kInactive{{0.0f, 0.0f, 0.0f}, 1.0f, {1.0f, 0.0f, 0.0f}, 0.0f};  ///< tnear > tfar

  /// How coherent spans are traced (BackendOptions::coherent_method).
  enum class Method { packet8, packet16, stream };

  static Method parse_method(const std::string& m) {
    if (m.empty() || m == "packet8") return Method::packet8;
    if (m == "packet16") return Method::packet16;
    if (m == "stream") return Method::stream;
    throw Error(cat("embree: unknown coherent method '", m, "' (packet8, packet16, stream)"));
  }

  /// True for the incoherent method "stream", false for "single" (the default).
  static bool parse_incoherent(const std::string& m) {
    if (m.empty() || m == "single") return false;
    if (m == "stream") return true;
    throw Error(cat("embree: unknown incoherent method '", m, "' (single, stream)"));
  }

  /// Ray i of the query as Embree sees it in a packet or stream: invalid rays are inactive.
  bool active(const QueryContext& q, size_t i) const noexcept { return valid_ray(q.rays[i]); }

  /// The same for occlusion, where a ray that hits a plane (answered beside Embree) is
  /// inactive too; `out` gets the answer of an inactive ray (1 when a plane occludes it).
  bool active(const QueryContext& q, size_t i, uint8_t& out) const noexcept {
    const bool valid = valid_ray(q.rays[i]), plane = valid && hits_plane(q.rays[i]);
    out = uint8_t(plane);
    return valid && !plane;
  }

  /// Coherent closest hits by N-wide packets (rtcIntersect8 or rtcIntersect16).
  template <typename RayHitN, size_t N>
  void intersect_packets(QueryContext& q, std::span<Hit> hits) const noexcept {
    for (size_t base = 0; base < hits.size(); base += N) {
      const size_t n = std::min(N, hits.size() - base);
      alignas(64) int valid[N];
      RayHitN rh;  // Embree's packet types carry their own alignment
      for (size_t i = 0; i < N; ++i) {
        const bool ok = i < n && active(q, base + i);
        valid[i] = ok ? -1 : 0;
        set_lane(rh.ray, i, ok ? q.rays[base + i] : kDummy, ok ? base + i : 0);
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
      }
      trace_packet(valid, &q.embree, &rh);
      for (size_t i = 0; i < n; ++i)
        if (valid[i]) settle(q, base + i, rh.hit.geomID[i], rh.hit.instID[0][i], rh.hit.primID[i], rh.ray.tfar[i],
                             rh.hit.u[i], rh.hit.v[i], hits[base + i]);
        else put_miss(hits[base + i]);
    }
  }

  /// Coherent any hits by N-wide packets (rtcOccluded8 or rtcOccluded16).
  template <typename RayN, size_t N>
  void occluded_packets(QueryContext& q, std::span<uint8_t> out) const noexcept {
    for (size_t base = 0; base < out.size(); base += N) {
      const size_t n = std::min(N, out.size() - base);
      alignas(64) int valid[N];
      RayN ray;
      for (size_t i = 0; i < N; ++i) {
        const bool ok = i < n && active(q, base + i, out[base + i]);
        valid[i] = ok ? -1 : 0;
        set_lane(ray, i, ok ? q.rays[base + i] : kDummy, ok ? base + i : 0);
      }
      trace_packet(valid, &q.embree, &ray);
      for (size_t i = 0; i < n; ++i)
        if (valid[i]) out[base + i] = uint8_t(ray.tfar[i] < 0.0f);
    }
  }

  void trace_packet(const int* valid, RTCIntersectContext* c, RTCRayHit8* p) const { rtcIntersect8(valid, scene_handle_, c, p); }
  void trace_packet(const int* valid, RTCIntersectContext* c, RTCRayHit16* p) const { rtcIntersect16(valid, scene_handle_, c, p); }
  void trace_packet(const int* valid, RTCIntersectContext* c, RTCRay8* p) const { rtcOccluded8(valid, scene_handle_, c, p); }
  void trace_packet(const int* valid, RTCIntersectContext* c, RTCRay16* p) const { rtcOccluded16(valid, scene_handle_, c, p); }

  /// Closest hits as one ray stream (rtcIntersect1M; for a coherent span the context carries
  /// the coherent flag, for the incoherent method "stream" not). An inactive ray has tnear >
  /// tfar, as Embree's stream API asks.
  void intersect_stream(QueryContext& q, std::span<Hit> hits) const noexcept {
    thread_local std::vector<RTCRayHit> stream;
    stream.resize(hits.size());
    for (size_t i = 0; i < hits.size(); ++i) {
      RTCRayHit& rh = stream[i];
      rh.ray = to_embree(active(q, i) ? q.rays[i] : kInactive, i);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect1M(scene_handle_, &q.embree, stream.data(), unsigned(hits.size()), sizeof(RTCRayHit));
    for (size_t i = 0; i < hits.size(); ++i) {
      const RTCRayHit& rh = stream[i];
      if (active(q, i)) settle(q, i, rh.hit.geomID, rh.hit.instID[0], rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v, hits[i]);
      else put_miss(hits[i]);
    }
  }

  /// Any hits as one ray stream (rtcOccluded1M, with the coherent flag or without as above).
  void occluded_stream(QueryContext& q, std::span<uint8_t> out) const noexcept {
    thread_local std::vector<RTCRay> stream;
    stream.resize(out.size());
    for (size_t i = 0; i < out.size(); ++i) stream[i] = to_embree(active(q, i, out[i]) ? q.rays[i] : kInactive, i);
    rtcOccluded1M(scene_handle_, &q.embree, stream.data(), unsigned(out.size()), sizeof(RTCRay));
    // An inactive ray keeps tfar = 0 (kInactive); an occluded one gets -inf.
    for (size_t i = 0; i < out.size(); ++i) out[i] |= uint8_t(stream[i].tfar < 0.0f);
  }

  static QueryContext context(std::span<const Ray> rays, Coherence coherence) {
    QueryContext q;
    rtcInitIntersectContext(&q.embree);
    if (coherence == Coherence::coherent) q.embree.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    q.rays = rays.data();
    return q;
  }

  /// `r` as an Embree ray searching [tnear, tfar] widened by kBand (Embree requires tnear >=
  /// 0, so a hit at exactly t = 0 stays open: an origin lying on a triangle), with id = `index`.
  static RTCRay to_embree(const Ray& r, size_t index) {
    RTCRay e;
    e.org_x = r.org.x; e.org_y = r.org.y; e.org_z = r.org.z;
    e.dir_x = r.dir.x; e.dir_y = r.dir.y; e.dir_z = r.dir.z;
    e.tnear = r.tnear * (1.0f - kBand); e.tfar = r.tfar * (1.0f + kBand);
    e.time = 0.0f; e.mask = ~0u; e.id = uint32_t(index); e.flags = 0;
    return e;
  }

  /// Lane i of an Embree packet from `r` (see to_embree).
  template <typename RayN>
  static void set_lane(RayN& p, size_t i, const Ray& r, size_t index) {
    const RTCRay e = to_embree(r, index);
    p.org_x[i] = e.org_x; p.org_y[i] = e.org_y; p.org_z[i] = e.org_z;
    p.dir_x[i] = e.dir_x; p.dir_y[i] = e.dir_y; p.dir_z[i] = e.dir_z;
    p.tnear[i] = e.tnear; p.tfar[i] = e.tfar;
    p.time[i] = e.time; p.mask[i] = e.mask; p.id[i] = e.id; p.flags[i] = e.flags;
  }

  /// Ray `index` of the query through rtcIntersect1 into `out`, Embree's tnear raised to
  /// `tnear_embree` when given (a retrace past a rejected hit, see settle).
  void intersect1(QueryContext& q, size_t index, Hit& out, float tnear_embree = -1.0f) const noexcept {
    RTCRayHit rh;
    rh.ray = to_embree(q.rays[index], index);
    if (tnear_embree >= 0.0f) rh.ray.tnear = tnear_embree;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_handle_, &q.embree, &rh);
    settle(q, index, rh.hit.geomID, rh.hit.instID[0], rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v, out,
           tnear_embree >= 0.0f);
  }

  /// `out` = {t, prim, u, v, inst}, member by member. A Hit assembled whole on the stack and
  /// copied is read back by a 16-byte load that its smaller stores cannot forward to: a
  /// store-forwarding stall per ray, which measurably cost primary rays' speed (figures:
  /// docs/notes/2026-11-29-figures-from-code-comments.md).
  static void put(Hit& out, float t, uint32_t prim, float u, float v, uint32_t inst) noexcept {
    out.t = t;
    out.prim_id = prim;
    out.u = u;
    out.v = v;
    out.instance_id = inst;
  }
  static void put_miss(Hit& out) noexcept { put(out, std::numeric_limits<float>::infinity(), kInvalidId, 0, 0, kNoInstance); }

  /// The closest hit Embree returned for ray `index`, in the scene numbering and the caller's
  /// interval (see kBand), into `out`. A triangle hit within kBand of an end is decided by the
  /// scalar test (its t, u, v are reported). When that test misses a hit near tnear, a
  /// closer-than-true t hid the ray's real first hit beyond: the ray is traced again from
  /// Embree's t, raised a step, once; a hit near tfar that the test misses means nothing lies
  /// in the interval. The unbounded planes, which live beside the Embree scene, then take the
  /// hit when closer.
  void settle(QueryContext& q, size_t index, unsigned geom, unsigned inst_geom, unsigned prim, float t, float u,
              float v, Hit& out, bool retraced = false) const noexcept {
    const Ray& r = q.rays[index];
    if (geom == RTC_INVALID_GEOMETRY_ID) {
      put_miss(out);
    } else {
      // In an instance, geom is the child scene's geometry (0), not the top scene's.
      const uint32_t inst = inst_geom == RTC_INVALID_GEOMETRY_ID ? kNoInstance : inst_geom - first_instance_geom_;
      const uint32_t prim_id =
          prim + (inst == kNoInstance ? geom_base_[geom] : scene_.mesh_base(scene_.instances()[inst].mesh));
      if (in_band(r, t)) [[unlikely]] return settle_band(q, index, t, prim_id, u, v, inst, out, retraced);
      if (t >= r.tnear && t <= r.tfar) put(out, t, prim_id, u, v, inst);
      else put_miss(out);  // outside the interval: never reported
    }
    scene_.intersect_planes(r, out);
  }

  /// settle for Embree's hit (t, u, v) on `prim_id` (of instance `inst`) within kBand of an
  /// end of ray `index`'s interval (rare, kept out of the common path): a triangle's hit
  /// decided by its own scalar test, on the ray it saw (in an instance, the object-space image).
  [[gnu::noinline]] void settle_band(QueryContext& q, size_t index, float t, uint32_t prim_id, float u, float v,
                                     uint32_t inst, Hit& out, bool retraced) const noexcept {
    const Ray& r = q.rays[index];
    if (scene_.locate(prim_id).kind == PrimKind::triangle) {
      const Ray tested = inst == kNoInstance ? r : object_ray(r, scene_.instances()[inst].world_to_object);
      if (const Intersection<float> s = scalar_triangle(scene_, prim_id, tested); s.hit) {
        put(out, s.t, prim_id, s.u, s.v, inst);
      } else if (t < r.tnear * (1.0f + kBand) && !retraced) {
        return intersect1(q, index, out, std::nextafter(std::max(t, r.tnear), std::numeric_limits<float>::infinity()));
      } else {
        put_miss(out);
      }
    } else if (t >= r.tnear && t <= r.tfar) {
      put(out, t, prim_id, u, v, inst);
    } else {
      put_miss(out);  // outside the interval and not a triangle's: never reported
    }
    scene_.intersect_planes(r, out);
  }

  /// A triangle geometry over mesh m (to be committed and attached), its buffers' bytes added
  /// to `buffer_bytes`. An instanced mesh's TriangleData gets its first_instance_geom once the
  /// world's geometries are attached (the constructor).
  RTCGeometry triangle_geometry(RTCDevice dev, uint32_t m, size_t& buffer_bytes) {
    const MeshView& mesh = scene_.meshes()[m];
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, geometry_quality_);
    const bool instanced = scene_.is_instanced(m);
    triangle_data_.push_back({&scene_, scene_.mesh_base(m), instanced ? 0u : kNoInstance});
    rtcSetGeometryUserData(g, &triangle_data_.back());
    rtcSetGeometryOccludedFilterFunction(g, occlusion_band_filter);
    if (instanced) rtcSetGeometryIntersectFilterFunction(g, instance_valid_filter);
    if (shares_positions(mesh)) {
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions.data(), 0,
                                 mesh.positions.stride(), mesh.positions.size());
    } else {
      auto* v = static_cast<Vec3f*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            sizeof(Vec3f), mesh.positions.size()));
      check(dev, "embree: vertex buffer");
      std::copy(mesh.positions.begin(), mesh.positions.end(), v);
      buffer_bytes += mesh.positions.size() * sizeof(Vec3f);
    }
    if (scene_.is_shared(m)) {
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.triangles.data(), 0,
                                 mesh.triangles.stride(), mesh.triangle_count());
    } else {
      auto* idx = static_cast<TriangleIndices*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, sizeof(TriangleIndices), mesh.triangle_count()));
      check(dev, "embree: index buffer");
      std::copy(mesh.triangles.begin(), mesh.triangles.end(), idx);
      buffer_bytes += mesh.triangle_count() * sizeof(TriangleIndices);
    }
    check(dev, "embree: triangle buffers");
    return g;
  }

  /// Commits `g`, attaches it to the top scene and returns its id there.
  unsigned attach(RTCGeometry g, uint32_t prim_base) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene_handle_, g);
    rtcReleaseGeometry(g);
    check(device_->handle, "embree: attach geometry");
    if (geom_base_.size() <= id) geom_base_.resize(id + 1, kInvalidId);
    geom_base_[id] = prim_base;
    return id;
  }

  template <typename Kind>
  void add_user(RTCDevice dev) {
    const uint32_t n = Kind::count(scene_);
    if (n == 0) return;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, n);
    rtcSetGeometryUserData(g, const_cast<UserData*>(&user_));
    rtcSetGeometryBoundsFunction(g, user_bounds<Kind>, nullptr);
    rtcSetGeometryIntersectFunction(g, user_intersect<Kind>);
    rtcSetGeometryOccludedFunction(g, user_occluded<Kind>);
    check(dev, "embree: user geometry");
    attach(g, Kind::base(scene_));
  }

  bool hits_plane(const Ray& r) const noexcept { return scene_.occluded_by_planes(r); }

  /// The variant's flags, and a context filter allowed (the queries with options set one;
  /// the others leave it null).
  RTCSceneFlags scene_flags() const { return RTCSceneFlags(flags_ | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION); }

  Numbering numbering() const { return {&scene_, &geom_base_, first_instance_geom_}; }

  /// Ray `index` through rtcIntersect1 or rtcOccluded1 (`occlusion`) as a query with options
  /// (Gated) of `mode`; true when Embree found an accepted hit.
  bool trace_gated(std::span<const Ray> rays, size_t index, Gated& g, bool occlusion) const {
    QueryContext q = context(rays, Coherence::incoherent);
    q.gated = &g;
    q.embree.filter = gated_filter;
    g.index = index;
    if (occlusion) {
      RTCRay ray = to_embree(rays[index], index);
      rtcOccluded1(scene_handle_, &q.embree, &ray);
      return ray.tfar < 0.0f;
    }
    RTCRayHit rh;
    rh.ray = to_embree(rays[index], index);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_handle_, &q.embree, &rh);
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }

  void trace_closest_filtered(std::span<const Ray> rays, std::span<Hit> hits,
                              const TraceOptions& options) const override {
    simd::FlushDenormals ftz;
    Gated g{Gated::Mode::closest, numbering(), options};
    for (size_t i = 0; i < rays.size(); ++i) {
      g.best = Hit{};
      if (valid_ray(rays[i])) trace_gated(rays, i, g, false);
      hits[i] = g.best;
    }
  }

  void trace_any_filtered(std::span<const Ray> rays, std::span<uint8_t> out,
                          const TraceOptions& options) const override {
    simd::FlushDenormals ftz;
    Gated g{Gated::Mode::any, numbering(), options};
    for (size_t i = 0; i < rays.size(); ++i) out[i] = valid_ray(rays[i]) && trace_gated(rays, i, g, true);
  }

  void trace_every(std::span<const Ray> rays, size_t index, const TraceOptions& options,
                   std::vector<Hit>& out) const override {
    simd::FlushDenormals ftz;
    Gated g{Gated::Mode::every, numbering(), options};
    g.every = &out;
    trace_gated(rays, index, g, false);
  }

  void closest_points_of(std::span<const PointQuery> queries, std::span<ClosestPoint> out) const override {
    simd::FlushDenormals ftz;
    for (size_t i = 0; i < queries.size(); ++i) {
      out[i] = ClosestPoint{};
      if (!valid_point_query(queries[i])) continue;
      PointSearch search(queries[i]);
      const Vec3f& p = search.point;
      // Embree 3.13.5 does not shrink the query inside an instance, nor cull instances it
      // should visit once a world primitive has shrunk the radius (seen: a closer instanced
      // triangle missed for a farther floor; every triangle of 16 instanced bunnies visited for
      // each point). So the instances come first, each whose box lies within the best distance
      // searched through its own scene, in its object space, with a radius that bounds the
      // world one there; then the top scene, within the best distance so far.
      for (uint32_t k = 0; k < scene_.instances().size(); ++k) {
        const Instance& in = scene_.instances()[k];
        const MeshGeometry& mg = mesh_geometry_[in.mesh];
        if (!mg.scene || box_distance(in.bounds, p) > std::min(search.best.distance, search.radius)) continue;
        const float scale = in.world_to_object.largest_stretch() * 1.00001f;
        point_query(mg.scene, in.world_to_object.point(p), std::min(search.best.distance, search.radius) * scale,
                    {numbering(), search, k, scale});
      }
      point_query(scene_handle_, p, std::min(search.best.distance, search.radius), {numbering(), search});
      out[i] = search.best;
    }
  }

  /// rtcPointQuery of `scene` at `p` (its space) within `radius`, into the context's search.
  static void point_query(RTCScene scene, const Vec3f& p, float radius, PointContext c) {
    RTCPointQuery q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    // Finite: Embree maps the query's sphere into instances, where an infinite radius becomes
    // NaN bounds. Every distance within the coordinate range is below 2^32; scaled into an
    // instance, below 2^52.
    q.radius = std::min(radius, 0x1p60f);
    q.time = 0.0f;
    RTCPointQueryContext pc;
    rtcInitPointQueryContext(&pc);
    rtcPointQuery(scene, &q, &pc, point_callback, &c);
  }

  /// Distance from p to box b (0 inside).
  static float box_distance(const Box3f& b, const Vec3f& p) {
    const Vec3f d = max(max(b.lo - p, p - b.hi), Vec3f(0.0f));
    return length(d);
  }

  const Scene& scene_;
  UserData user_;
  std::vector<TriangleData> triangle_data_;  ///< one per triangle geometry, for its filter
  Device* device_ = nullptr;
  RTCScene scene_handle_ = nullptr;
  std::vector<uint32_t> geom_base_;
  std::vector<RTCScene> children_;   ///< an instanced mesh's child scene each
  std::vector<MeshGeometry> mesh_geometry_;  ///< per mesh of the scene
  std::vector<uint64_t> instance_meshes_;    ///< the mesh_uid each instance placed at the build
  RTCSceneFlags flags_ = RTC_SCENE_FLAG_NONE;
  RTCBuildQuality quality_ = RTC_BUILD_QUALITY_MEDIUM;           ///< the scenes'
  RTCBuildQuality geometry_quality_ = RTC_BUILD_QUALITY_MEDIUM;  ///< the triangle geometries'
  uint32_t first_instance_geom_ = 0;  ///< instance i is geometry first_instance_geom_ + i of the top scene
  bool coherent_occlusion_ = true;    ///< occlusion queries may carry the coherent flag (see occluded)
  Method method_;
  bool incoherent_stream_;  ///< incoherent batches by rtcIntersect1M/rtcOccluded1M without the coherent flag
  BackendInfo info_;
};

}  // namespace

std::vector<std::string> variants() { return {"default", "robust", "compact", "high", "dynamic"}; }

std::vector<std::string> coherent_methods() { return {"packet8", "packet16", "stream"}; }

std::vector<std::string> incoherent_methods() { return {"single", "stream"}; }

std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options) {
  return std::make_unique<EmbreeBackend>(scene, options);
}

}  // namespace rp::embree
