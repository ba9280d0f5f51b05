#include "backends/embree/embree_backend.h"

#include <embree3/rtcore.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <mutex>

#include "engine/error.h"

namespace rp::embree {

namespace {

/// One Embree device per configuration string, alive for the whole process. Embree reports
/// errors through a callback (it cannot throw through C); the message is kept per thread and
/// turned into rp::Error by check() after each API call that can fail.
struct Device {
  RTCDevice handle = nullptr;
  std::atomic<int64_t> bytes{0};  ///< live bytes allocated by this device (memory monitor)
};

thread_local std::string t_last_error;

void on_error(void*, RTCError code, const char* message) {
  t_last_error = cat("embree error ", int(code), ": ", message ? message : "(no message)");
}

bool on_memory(void* user, ssize_t bytes, bool) {
  static_cast<Device*>(user)->bytes.fetch_add(bytes, std::memory_order_relaxed);
  return true;
}

void check(RTCDevice device, const char* what) {
  const RTCError code = rtcGetDeviceError(device);
  if (code != RTC_ERROR_NONE) {
    std::string msg = t_last_error.empty() ? cat("embree error ", int(code)) : t_last_error;
    t_last_error.clear();
    throw Error(cat(what, ": ", msg));
  }
}

Device& device_for(const std::string& config) {
  static std::mutex mutex;
  // Never destroyed: a backend held in a static (a benchmark fixture, say) may release its
  // scene during exit, after function-local statics built later than it are gone.
  static auto* devices = new std::map<std::string, std::unique_ptr<Device>>;
  std::lock_guard lock(mutex);
  std::unique_ptr<Device>& d = (*devices)[config];
  if (!d) {
    auto created = std::make_unique<Device>();
    created->handle = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!created->handle) {
      RTCError code = rtcGetDeviceError(nullptr);
      throw Error(cat("embree: cannot create a device with config '", config, "' (error ", int(code), ")"));
    }
    rtcSetDeviceErrorFunction(created->handle, on_error, nullptr);
    rtcSetDeviceMemoryMonitorFunction(created->handle, on_memory, created.get());
    d = std::move(created);
  }
  return *d;
}

/// Flush-to-zero and denormals-are-zero for the calling thread while it traces, as Embree
/// asks of every thread that calls it; the caller's MXCSR is restored afterwards.
class FlushDenormals {
 public:
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
  ~FlushDenormals() { _mm_setcsr(saved_); }
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  unsigned int saved_;
};

/// What the user-geometry callbacks see: the scene and the kind's first prim_id.
struct UserData {
  const Scene* scene;
};

/// The analytic kinds Embree sees as user geometry: the kind's prim_id range in the scene.
struct SphereKind {
  static uint32_t base(const Scene& s) { return s.sphere_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.spheres().size()); }
};
struct QuadricKind {
  static uint32_t base(const Scene& s) { return s.quadric_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.quadrics().size()); }
};
struct PolygonKind {
  static uint32_t base(const Scene& s) { return s.polygon_base(); }
  static uint32_t count(const Scene& s) { return uint32_t(s.polygons().size()); }
};

template <typename Kind>
void user_bounds(const RTCBoundsFunctionArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  const Box3f b = s.prim_bounds(Kind::base(s) + a->primID);
  *a->bounds_o = {b.lo.x, b.lo.y, b.lo.z, 0.0f, b.hi.x, b.hi.y, b.hi.z, 0.0f};
}

inline Ray ray_from(RTCRayN* rays, unsigned n, unsigned i) {
  return {{RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i)},
          RTCRayN_tnear(rays, n, i),
          {RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i)},
          RTCRayN_tfar(rays, n, i)};
}

template <typename Kind>
void user_intersect(const RTCIntersectFunctionNArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  RTCRayN* rays = RTCRayHitN_RayN(a->rayhit, a->N);
  RTCHitN* hits = RTCRayHitN_HitN(a->rayhit, a->N);
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    const Intersection<float> h = s.intersect_analytic(Kind::base(s) + a->primID, ray_from(rays, a->N, i));
    if (!h.hit) continue;
    RTCRayN_tfar(rays, a->N, i) = h.t;
    RTCHitN_u(hits, a->N, i) = h.u;
    RTCHitN_v(hits, a->N, i) = h.v;
    RTCHitN_Ng_x(hits, a->N, i) = 0.0f;
    RTCHitN_Ng_y(hits, a->N, i) = 0.0f;
    RTCHitN_Ng_z(hits, a->N, i) = 0.0f;
    RTCHitN_primID(hits, a->N, i) = a->primID;
    RTCHitN_geomID(hits, a->N, i) = a->geomID;
    RTCHitN_instID(hits, a->N, i, 0) = a->context->instID[0];
  }
}

/// Embree is given the float below the caller's tnear (see EmbreeBackend::embree_tnear); in
/// occlusion queries, which are never retraced, this gives the caller's tnear back.
/// (Ambiguous only for the single value tnear = FLT_MIN, which comes back one float higher.)
inline float caller_tnear(float embree_tnear) {
  return embree_tnear >= std::numeric_limits<float>::min()
             ? std::nextafter(embree_tnear, std::numeric_limits<float>::infinity())
             : embree_tnear;
}

/// Occlusion filter on triangle geometry: rejects a hit below the caller's tnear, which the
/// lowered Embree tnear lets through. Embree sets the ray's tfar to the candidate hit's
/// distance before calling a filter.
void occlusion_tnear_filter(const RTCFilterFunctionNArguments* a) {
  for (unsigned i = 0; i < a->N; ++i)
    if (a->valid[i] != 0 && !(RTCRayN_tfar(a->ray, a->N, i) >= caller_tnear(RTCRayN_tnear(a->ray, a->N, i))))
      a->valid[i] = 0;
}

template <typename Kind>
void user_occluded(const RTCOccludedFunctionNArguments* a) {
  const Scene& s = *static_cast<const UserData*>(a->geometryUserPtr)->scene;
  for (unsigned i = 0; i < a->N; ++i) {
    if (a->valid[i] == 0) continue;
    Ray r = ray_from(a->ray, a->N, i);
    r.tnear = caller_tnear(r.tnear);
    if (s.intersect_analytic(Kind::base(s) + a->primID, r).hit)
      RTCRayN_tfar(a->ray, a->N, i) = -std::numeric_limits<float>::infinity();
  }
}

class EmbreeBackend final : public Backend {
 public:
  EmbreeBackend(const Scene& scene, const BackendOptions& options) : scene_(scene), user_{&scene} {
    const auto start = std::chrono::steady_clock::now();
    info_.name = "embree";
    info_.variant = options.variant;
    RTCSceneFlags flags = RTC_SCENE_FLAG_NONE;
    RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;
    if (options.variant == "robust") flags = RTC_SCENE_FLAG_ROBUST;
    else if (options.variant == "compact") flags = RTC_SCENE_FLAG_COMPACT;
    else if (options.variant == "high") quality = RTC_BUILD_QUALITY_HIGH;
    else if (options.variant != "default")
      throw Error(cat("embree: unknown variant '", options.variant, "' (default, robust, compact, high)"));

    device_ = &device_for(options.device_config);
    RTCDevice dev = device_->handle;
    // Embree's memory monitor is per device: serialise builds so the delta is this scene's.
    static std::mutex build_mutex;
    std::lock_guard lock(build_mutex);
    const int64_t bytes_before = device_->bytes.load();
    size_t buffer_bytes = 0;

    scene_handle_ = rtcNewScene(dev);
    check(dev, "embree: rtcNewScene");
    rtcSetSceneFlags(scene_handle_, flags);
    rtcSetSceneBuildQuality(scene_handle_, quality);

    for (size_t m = 0; m < scene.meshes().size(); ++m) {
      const TriangleMesh& mesh = scene.meshes()[m];
      if (mesh.triangle_count() == 0) continue;
      RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetGeometryBuildQuality(g, quality);
      rtcSetGeometryOccludedFilterFunction(g, occlusion_tnear_filter);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                             3 * sizeof(float), mesh.positions.size()));
      auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                  3 * sizeof(uint32_t), mesh.triangle_count()));
      check(dev, "embree: triangle buffers");
      std::copy_n(&mesh.positions[0].x, 3 * mesh.positions.size(), v);
      std::copy(mesh.indices.begin(), mesh.indices.end(), idx);
      buffer_bytes += mesh.positions.size() * 12 + mesh.indices.size() * 4;
      attach(g, scene.mesh_base(m));
    }
    add_user<SphereKind>(dev);
    add_user<QuadricKind>(dev);
    add_user<PolygonKind>(dev);

    rtcCommitScene(scene_handle_);
    check(dev, "embree: rtcCommitScene");
    const int64_t delta = device_->bytes.load() - bytes_before;
    info_.bytes = delta > int64_t(buffer_bytes) ? size_t(delta) - buffer_bytes : 0;
    info_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  ~EmbreeBackend() override {
    if (scene_handle_) rtcReleaseScene(scene_handle_);
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Coherence coherence) const noexcept override {
    FlushDenormals ftz;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (coherence == Coherence::coherent) {
      ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      for (size_t base = 0; base < rays.size(); base += 8) {
        const size_t n = std::min<size_t>(8, rays.size() - base);
        alignas(32) int valid[8];
        alignas(32) RTCRayHit8 rh;
        for (size_t i = 0; i < 8; ++i) {
          const bool ok = i < n && valid_ray(rays[base + i]);
          valid[i] = ok ? -1 : 0;
          set_lane(rh.ray, i, ok ? rays[base + i] : kDummy);
          rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(valid, scene_handle_, &ctx, &rh);
        for (size_t i = 0; i < n; ++i) {
          const Ray& r = rays[base + i];
          if (!valid[i]) hits[base + i] = Hit{};
          else if (rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID && rh.ray.tfar[i] < r.tnear) hits[base + i] = intersect1(r, ctx, r.tnear);
          else hits[base + i] = finish(r, rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i], rh.hit.u[i], rh.hit.v[i]);
        }
      }
    } else {
      for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        if (!valid_ray(r)) { hits[i] = Hit{}; continue; }
        hits[i] = intersect1(r, ctx);
      }
    }
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> out, Coherence coherence) const noexcept override {
    FlushDenormals ftz;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (coherence == Coherence::coherent) {
      ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      for (size_t base = 0; base < rays.size(); base += 8) {
        const size_t n = std::min<size_t>(8, rays.size() - base);
        alignas(32) int valid[8];
        alignas(32) RTCRay8 ray;
        for (size_t i = 0; i < 8; ++i) {
          const bool ok = i < n && valid_ray(rays[base + i]) && !hits_plane(rays[base + i]);
          valid[i] = ok ? -1 : 0;
          set_lane(ray, i, ok ? rays[base + i] : kDummy);
        }
        rtcOccluded8(valid, scene_handle_, &ctx, &ray);
        for (size_t i = 0; i < n; ++i) {
          const Ray& r = rays[base + i];
          out[base + i] = valid[i] ? uint8_t(ray.tfar[i] < 0.0f) : uint8_t(valid_ray(r) && hits_plane(r));
        }
      }
    } else {
      for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        if (!valid_ray(r)) { out[i] = 0; continue; }
        if (hits_plane(r)) { out[i] = 1; continue; }
        RTCRay ray = to_embree(r, embree_tnear(r.tnear));
        rtcOccluded1(scene_handle_, &ctx, &ray);
        out[i] = uint8_t(ray.tfar < 0.0f);
      }
    }
  }

  const BackendInfo& info() const noexcept override { return info_; }

 private:
  static constexpr Ray kDummy{{0.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 0.0f};

  /// Embree's triangle tests accept tnear < t <= tfar; raypack's convention closes the
  /// interval at tnear too. Embree is therefore given the float just below tnear, and any hit
  /// it returns below the caller's tnear is traced again with tnear itself; occlusion
  /// queries instead reject such hits in a filter (occlusion_tnear_filter, and user_occluded
  /// for analytic primitives). One case stays open: tnear == 0 (Embree requires tnear >= 0,
  /// so a triangle hit at exactly t = 0, an origin lying on the triangle, is missed). A
  /// tnear up to the smallest normal float is passed unchanged (open there).
  static float embree_tnear(float tnear) {
    return tnear > std::numeric_limits<float>::min() ? std::nextafter(tnear, 0.0f) : tnear;
  }

  /// `r` as an Embree ray with the given tnear.
  static RTCRay to_embree(const Ray& r, float tnear) {
    RTCRay e;
    e.org_x = r.org.x; e.org_y = r.org.y; e.org_z = r.org.z;
    e.dir_x = r.dir.x; e.dir_y = r.dir.y; e.dir_z = r.dir.z;
    e.tnear = tnear; e.tfar = r.tfar;
    e.time = 0.0f; e.mask = ~0u; e.id = 0; e.flags = 0;
    return e;
  }

  /// Lane i of an Embree packet from `r` (tnear lowered as embree_tnear() says).
  static void set_lane(RTCRay8& p, size_t i, const Ray& r) {
    const RTCRay e = to_embree(r, embree_tnear(r.tnear));
    p.org_x[i] = e.org_x; p.org_y[i] = e.org_y; p.org_z[i] = e.org_z;
    p.dir_x[i] = e.dir_x; p.dir_y[i] = e.dir_y; p.dir_z[i] = e.dir_z;
    p.tnear[i] = e.tnear; p.tfar[i] = e.tfar;
    p.time[i] = e.time; p.mask[i] = e.mask; p.id[i] = e.id; p.flags[i] = e.flags;
  }

  /// One ray through rtcIntersect1 with the given Embree tnear (default: one step lower);
  /// a hit below the caller's tnear is retraced with tnear itself.
  Hit intersect1(const Ray& r, RTCIntersectContext& ctx, float tnear_embree = -1.0f) const noexcept {
    RTCRayHit rh;
    rh.ray = to_embree(r, tnear_embree >= 0.0f ? tnear_embree : embree_tnear(r.tnear));
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_handle_, &ctx, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && rh.ray.tfar < r.tnear && tnear_embree < 0.0f)
      return intersect1(r, ctx, r.tnear);
    return finish(r, rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
  }

  void attach(RTCGeometry g, uint32_t prim_base) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene_handle_, g);
    rtcReleaseGeometry(g);
    check(device_->handle, "embree: attach geometry");
    if (geom_base_.size() <= id) geom_base_.resize(id + 1, kInvalidId);
    geom_base_[id] = prim_base;
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

  /// Maps Embree's (geomID, primID) to the scene numbering, then lets the unbounded planes,
  /// which live beside the Embree scene, take the hit when they are closer.
  Hit finish(const Ray& r, unsigned geom, unsigned prim, float t, float u, float v) const noexcept {
    Hit h;
    if (geom != RTC_INVALID_GEOMETRY_ID) h = {t, geom_base_[geom] + prim, u, v};
    scene_.intersect_planes(r, h);
    return h;
  }

  bool hits_plane(const Ray& r) const noexcept { return scene_.occluded_by_planes(r); }

  const Scene& scene_;
  UserData user_;
  Device* device_ = nullptr;
  RTCScene scene_handle_ = nullptr;
  std::vector<uint32_t> geom_base_;
  BackendInfo info_;
};

}  // namespace

std::vector<std::string> variants() { return {"default", "robust", "compact", "high"}; }

std::unique_ptr<Backend> make_backend(const Scene& scene, const BackendOptions& options) {
  return std::make_unique<EmbreeBackend>(scene, options);
}

}  // namespace rp::embree
