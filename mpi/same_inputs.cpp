#include "mpi/same_inputs.h"

#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "base/error.h"
#include "io/input_file.h"

namespace rp::dist {

namespace {

/// XXH3 streaming over a scene's values, field by field: structs with padding are never fed
/// whole (their padding bytes are not part of the value).
class Hasher {
 public:
  Hasher() : state_(XXH3_createState()) {
    if (!state_) throw std::bad_alloc();
    XXH3_64bits_reset(state_);
  }
  ~Hasher() { XXH3_freeState(state_); }
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;

  void bytes(const void* p, size_t n) { XXH3_64bits_update(state_, p, n); }
  /// A value of a type without padding (asserted by size), as its bytes.
  template <typename T>
  void raw(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof v);
  }
  /// An array of such values, with its length first (so [a][b] and [ab] differ).
  template <typename T>
  void array(const std::vector<T>& v) {
    raw(uint64_t(v.size()));
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  /// Strided items likewise: the same values give the same hash whatever their stride.
  template <typename T>
  void items(const Strided<T>& v) {
    raw(uint64_t(v.size()));
    if (v.stride() == sizeof(T))
      bytes(v.data(), v.size() * sizeof(T));
    else
      for (const T& x : v) raw(x);
  }
  void text(const std::string& s) {
    raw(uint64_t(s.size()));
    bytes(s.data(), s.size());
  }
  uint64_t digest() const { return XXH3_64bits_digest(state_); }

 private:
  XXH3_state_t* state_;
};

// The types fed whole: floats and 32-bit integers only, so no padding.
static_assert(sizeof(Vec3f) == 12 && sizeof(Vec2f) == 8);
static_assert(sizeof(Sphere) == 20 && sizeof(Plane) == 20);
static_assert(sizeof(QuadricShape) == 4 * (10 + 3 + 6) + 4);
static_assert(sizeof(PointLight) == 24 && sizeof(DirectionalLight) == 24);
static_assert(sizeof(Affine3f) == 48 && sizeof(Affine3d) == 96);

}  // namespace

namespace {

void hash_scene(Hasher& h, const Scene& scene) {
  h.raw(uint64_t(scene.materials().size()));
  for (const Material& m : scene.materials()) {
    h.text(m.name);
    for (const float f : {m.diffuse.x, m.diffuse.y, m.diffuse.z, m.specular.x, m.specular.y, m.specular.z, m.shininess,
                          m.emission.x, m.emission.y, m.emission.z, m.mirror, m.ior, m.opacity})
      h.raw(f);
  }
  h.raw(uint64_t(scene.meshes().size()));
  for (const MeshView& m : scene.meshes()) {
    h.text(m.name);
    h.items(m.positions);
    h.items(m.triangles);
    h.items(m.normals);
    h.items(m.uvs);
    h.items(m.face_materials);
    h.raw(m.material);
  }
  h.array(scene.spheres());
  h.array(scene.quadrics());
  h.raw(uint64_t(scene.polygons().size()));
  for (const PolygonShape& p : scene.polygons())  // the plane follows from the vertices
    for (const uint32_t v : {p.first, p.count, uint32_t(p.convex), p.material}) h.raw(v);
  h.array(scene.polygon_vertices());
  h.array(scene.planes());
  h.raw(uint64_t(scene.instances().size()));
  for (const Instance& i : scene.instances()) {  // the rest of an instance follows from these
    h.raw(i.mesh);
    h.raw(i.object_to_world);
  }
  h.array(scene.point_lights());
  h.array(scene.directional_lights());
  h.raw(uint8_t(scene.camera().has_value()));
  if (const std::optional<CameraDesc>& c = scene.camera()) {
    for (const float f : {c->eye.x, c->eye.y, c->eye.z, c->look_at.x, c->look_at.y, c->look_at.z, c->up.x, c->up.y,
                          c->up.z, c->vfov_degrees, c->fisheye_fov_degrees, c->aperture, c->focus_distance})
      h.raw(f);
    h.raw(uint8_t(c->model));
  }
  h.raw(int32_t(scene.up_axis()));
}

void hash_animation(Hasher& h, const SceneAnimation& animation) {
  h.raw(uint64_t(animation.curves().size()));
  for (const AnimationCurve& c : animation.curves()) {
    h.raw(uint8_t(c.property));
    h.raw(uint8_t(c.interpolation));
    h.array(c.times);
    h.array(c.values);
  }
  h.raw(uint64_t(animation.nodes().size()));
  for (const AnimatedNode& n : animation.nodes()) {
    h.raw(int32_t(n.parent));
    h.raw(n.base);
    h.raw(n.curves);
    h.raw(n.rest.translation);
    h.raw(n.rest.rotation);
    h.raw(n.rest.scale);
    h.raw(n.local);
  }
  h.raw(uint64_t(animation.targets().size()));
  for (const AnimatedTarget& t : animation.targets()) {
    h.raw(uint8_t(t.kind));
    for (const uint32_t v : {t.node, t.index}) h.raw(v);
    h.raw(t.power);
    for (const float f :
         {t.camera.vfov_degrees, t.camera.fisheye_fov_degrees, t.camera.aperture, t.camera.focus_distance})
      h.raw(f);
    h.raw(uint8_t(t.camera.model));
  }
}

}  // namespace

uint64_t scene_digest(const Scene& scene) {
  Hasher h;
  hash_scene(h, scene);
  return h.digest();
}

uint64_t scene_digest(const Scene& scene, const SceneAnimation& animation) {
  Hasher h;
  hash_scene(h, scene);
  hash_animation(h, animation);
  return h.digest();
}

uint64_t file_digest(const std::string& path) {
  constexpr uint64_t kBlock = 64 << 10;
  constexpr int kBlocks = 64;
  uint64_t size = 0;
  const int fd = open_regular_file(path, size);
  Hasher h;
  h.raw(size);
  std::vector<char> block(kBlock);
  for (int b = 0; b < kBlocks && size > 0; ++b) {
    // Blocks 0 and kBlocks-1 are the file's first and last; the rest evenly between.
    const uint64_t span = size > kBlock ? size - kBlock : 0;
    const uint64_t at = span / (kBlocks - 1) * uint64_t(b) + (b == kBlocks - 1 ? span % (kBlocks - 1) : 0);
    const size_t want = size_t(std::min(kBlock, size - at));
    size_t got = 0;
    while (got < want) {
      const ssize_t n = ::pread(fd, block.data() + got, want - got, off_t(at + got));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int e = n < 0 ? errno : EIO;
        ::close(fd);
        throw Error(cat(path, ": cannot read: ", std::strerror(e)));
      }
      got += size_t(n);
    }
    h.bytes(block.data(), want);
    if (size <= kBlock) break;  // one block holds it all
  }
  ::close(fd);
  return h.digest();
}

void check_same_inputs(const Comm& comm, const std::vector<InputDigest>& inputs) {
  if (comm.size() == 1) return;
  std::string digests(inputs.size() * sizeof(uint64_t), '\0');
  for (size_t i = 0; i < inputs.size(); ++i)
    std::memcpy(&digests[i * sizeof(uint64_t)], &inputs[i].digest, sizeof(uint64_t));
  comm.broadcast(digests);  // rank 0's
  together(comm, [&] {
    for (size_t i = 0; i < inputs.size(); ++i) {
      uint64_t root = 0;
      std::memcpy(&root, &digests[i * sizeof(uint64_t)], sizeof root);
      if (root != inputs[i].digest)
        throw Error(cat(inputs[i].flag, " ", inputs[i].path,
                        ": not what rank 0 read (another file under the same path on this rank's node?)"));
    }
  });
}

}  // namespace rp::dist
