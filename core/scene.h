#pragma once
/// The scene model: flat arrays per primitive kind, one primitive numbering, materials,
/// lights and an optional camera. Backend-free: backends build their structures from it.
///
/// Primitive numbering (prim_id): the triangles of every mesh in mesh order, then spheres,
/// quadrics, polygons and planes, each kind in insertion order. Scene::locate() maps an id
/// back to its kind and index.
///
/// Instancing: a mesh is either a world mesh (add_mesh: its positions are world coordinates)
/// or an instanced mesh (add_instanced_mesh: its positions are in its own object space, and
/// it is in the world only where an Instance places it). An instanced mesh is stored once
/// however many instances place it, and its triangles keep their prim_ids in every placement;
/// a hit names the placement by Hit::instance_id, the index of the instance in instances()
/// (kNoInstance for every other primitive). Analytic primitives and planes are world-space only.

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "base/bbox.h"
#include "base/math.h"
#include "base/strided.h"
#include "core/affine.h"
#include "core/geometry/intersection.h"
#include "core/geometry/polygon.h"
#include "core/geometry/quadric.h"
#include "core/queries.h"
#include "core/ray.h"

namespace rp {

/// Blinn-Phong material with Whitted-style mirror and glass terms (the OBJ/MTL subset).
struct Material {
  std::string name;
  Vec3f diffuse{0.8f};      ///< Kd, albedo in [0, 1]
  Vec3f specular{0.0f};     ///< Ks
  float shininess = 32.0f;  ///< Ns, Blinn-Phong exponent (>= 0)
  Vec3f emission{0.0f};     ///< Ke, added unlit
  float mirror = 0.0f;      ///< fraction reflected as a perfect mirror, [0, 1]
  float ior = 1.0f;         ///< Ni, index of refraction (>= 1)
  float opacity = 1.0f;     ///< d, 1 = opaque
};

/// Isotropic point light; irradiance at distance r is intensity / r^2.
struct PointLight {
  Vec3f position;
  Vec3f intensity{1.0f};
};

/// Light from infinitely far away along `direction` (pointing from the light into the scene).
struct DirectionalLight {
  Vec3f direction{0.0f, -1.0f, 0.0f};
  Vec3f irradiance{1.0f};
};

/// Indexed triangle mesh that owns its arrays (what the loaders build; Scene::add_mesh takes
/// it). Normals and uvs are stored only when the source has them (empty otherwise, else one
/// per vertex); face_materials likewise (empty = `material` for all).
/// Bytes: 12 per vertex + 12 per triangle, plus 12/8/4 for normals/uvs/face materials.
struct TriangleMesh {
  std::string name;
  std::vector<Vec3f> positions;
  std::vector<uint32_t> indices;  ///< 3 per triangle, each < positions.size()
  std::vector<Vec3f> normals;
  std::vector<Vec2f> uvs;
  std::vector<uint32_t> face_materials;
  uint32_t material = 0;

  uint32_t triangle_count() const { return uint32_t(indices.size() / 3); }
  Vec3f vertex(uint32_t tri, int corner) const { return positions[indices[3 * tri + corner]]; }
};

/// The three vertex indices of a triangle.
using TriangleIndices = std::array<uint32_t, 3>;

/// A mesh as a scene holds it (Scene::meshes): views of its arrays, which are the scene's
/// own copy of a TriangleMesh (Scene::add_mesh) or the caller's buffers, shared without a
/// copy (Scene::add_shared_mesh, as Embree's rtcSetSharedGeometryBuffer). The fields mean
/// what TriangleMesh's do, a triangle's indices being one item of `triangles`.
struct MeshView {
  std::string name;
  Strided<Vec3f> positions;
  Strided<TriangleIndices> triangles;  ///< each index < positions.size()
  Strided<Vec3f> normals;              ///< empty, or one per vertex
  Strided<Vec2f> uvs;                  ///< empty, or one per vertex
  Strided<uint32_t> face_materials;    ///< empty, or one per triangle
  uint32_t material = 0;

  uint32_t triangle_count() const { return uint32_t(triangles.size()); }
  Vec3f vertex(uint32_t tri, int corner) const { return positions[triangles[tri][corner]]; }
};

/// A TriangleMesh holding a copy of `m`'s arrays.
TriangleMesh to_triangle_mesh(const MeshView& m);

struct Sphere {
  Vec3f center;
  float radius = 1.0f;  ///< > 0
  uint32_t material = 0;
};

/// A general quadric clipped to its box (see core/geometry/quadric.h).
struct QuadricShape {
  Quadric<float> quadric;
  uint32_t material = 0;
};

/// Unbounded plane n.P + d = 0, visible from both sides.
struct Plane {
  Vec3f normal{0.0f, 1.0f, 0.0f};
  float d = 0.0f;
  uint32_t material = 0;
};

/// Planar polygon: vertices [first, first + count) of Scene::polygon_vertices().
struct PolygonShape {
  uint32_t first = 0, count = 0;
  PolygonPlane<float> plane;
  bool convex = false;
  uint32_t material = 0;
};

/// A placement of an instanced mesh (Scene::add_instance). 128 bytes.
struct Instance {
  uint32_t mesh = 0;         ///< index into Scene::meshes(), an instanced mesh
  Affine3f object_to_world;  ///< as given
  /// Its inverse, computed in float as Embree computes it (rp::float_inverse): what every
  /// backend applies to a world ray (rp::object_ray) to trace it through the mesh.
  Affine3f world_to_object;
  /// +1, or -1 when object_to_world mirrors (negative determinant): the geometric normal of
  /// a hit is sign * normalize(world_to_object_L^T n), which points where the normal of the
  /// same triangle baked into world space (its corners mapped) would.
  float orientation = 1.0f;
  /// The image of the mesh's box (its 8 corners mapped in double, rounded outward).
  Box3f bounds;
};

/// How a camera maps image positions to rays (render/camera.h).
enum class CameraModel : uint8_t {
  pinhole,    ///< the lecture notes' planar projection
  panoramic,  ///< cylindrical, 360 degrees around the up axis
  fisheye,    ///< equidistant: angle from the view axis proportional to image radius
  thin_lens,  ///< pinhole placement with a lens of radius `aperture` focused at `focus_distance`
};

/// Camera placement and model: eye, look-at point, up vector, vertical field of view, and
/// the parameters of the non-pinhole models.
struct CameraDesc {
  Vec3f eye{0.0f, 0.0f, 5.0f};
  Vec3f look_at{0.0f};
  Vec3f up{0.0f, 1.0f, 0.0f};
  float vfov_degrees = 45.0f;  ///< in (0, 180); the panoramic camera's vertical extent too
  CameraModel model = CameraModel::pinhole;
  float fisheye_fov_degrees = 180.0f;  ///< fisheye: field of view across the image circle, (0, 360]
  float aperture = 0.0f;               ///< thin lens: lens radius in world units, >= 0
  float focus_distance = 0.0f;         ///< thin lens: distance of the plane in focus; 0 = |look_at - eye|
};

enum class PrimKind : uint8_t { triangle, sphere, quadric, polygon, plane };
const char* to_string(PrimKind k);

/// The most an instance's transform, or its inverse, may stretch (largest row sum of |L|):
/// 2^20, so that an instance's object space and the world stay within a factor of 2^20 of
/// each other.
inline constexpr float kMaxInstanceScale = 0x1p20f;

/// Where a prim_id lives: its kind, the index of the shape of that kind (mesh index for
/// triangles) and, for triangles, the triangle index within the mesh.
struct PrimLocation {
  PrimKind kind;
  uint32_t shape;
  uint32_t local;
};

/// A scene's orientation: which world axis points up, which way the model faces (`front`,
/// where a camera that frames it stands) and `right` = up x front, as unit axis vectors.
/// Y up faces +Z (the Stanford models, glTF's convention); Z up faces -Y (as Blender's and
/// most CAD and scanning tools' front views look along +Y); X up faces +Z.
struct UpFrame {
  Vec3f right, up, front;
};
/// The frame of up axis `axis` (0 x, 1 y, 2 z).
UpFrame up_frame(int axis);

/// Geometric data of a hit that the renderer and diff need beyond t/u/v/prim_id.
struct SurfacePoint {
  Vec3f position;
  Vec3f geometric_normal;  ///< unit length, as the primitive orients it (not face-forwarded)
  Vec3f shading_normal;    ///< unit; interpolated vertex normals when the mesh has them
  uint32_t material = 0;
};

class Scene {
 public:
  /// A scene starts with material 0, the default grey Material.
  Scene() { materials_.push_back(Material{.name = "default"}); }
  /// Adds a material and returns its index.
  uint32_t add_material(Material m);
  /// Validates (indices in range, positions within the coordinate range of core/ray.h,
  /// matching attribute sizes, material ids) and appends a world mesh; returns its index.
  /// Throws rp::Error naming the mesh on bad data. Every add_* refuses geometry outside the
  /// coordinate range, where the float kernels could overflow.
  uint32_t add_mesh(TriangleMesh mesh);
  /// The same checks, for a mesh in its own object space that only instances place
  /// (add_instance); returns its index. Its triangles take prim_ids as a world mesh's do.
  uint32_t add_instanced_mesh(TriangleMesh mesh);
  /// add_mesh and add_instanced_mesh of a copy of `mesh`'s arrays (to_triangle_mesh), e.g. a
  /// mesh of another scene.
  uint32_t add_mesh(const MeshView& mesh) { return add_mesh(to_triangle_mesh(mesh)); }
  uint32_t add_instanced_mesh(const MeshView& mesh) { return add_instanced_mesh(to_triangle_mesh(mesh)); }
  /// A world mesh whose arrays stay in the caller's buffers (strided views, no copy; Embree's
  /// shared buffers), checked as add_mesh checks a TriangleMesh, and each view for its layout
  /// (Strided::fits: 4-byte aligned start and stride, stride at least the item's size).
  /// Lifetime: the buffers must stay valid, and unchanged but as vertices_changed() allows,
  /// for as long as this scene, a copy of it or a backend built over either is used; the scene
  /// never writes them. A copy of the scene shares them too. The embree backend shares the
  /// triangles, and the positions when their stride is 16 bytes or more (Embree reads 16
  /// bytes at each vertex: the last position's record must then be 16 bytes long); it copies
  /// narrower positions.
  uint32_t add_shared_mesh(const MeshView& mesh);
  /// As add_shared_mesh, for an instanced mesh (add_instanced_mesh).
  uint32_t add_shared_instanced_mesh(const MeshView& mesh);
  /// The caller has written new positions (and normals) into shared mesh i's buffers, in
  /// place, as set_vertices gives new ones to a mesh the scene owns: checks them as
  /// set_vertices does and raises the version, so that backends update (Backend::update).
  /// The triangles, uvs and face materials must not change (remove the mesh and add it again).
  /// On bad data it throws rp::Error naming the mesh and vertex and changes nothing (the
  /// version stays): the buffers then hold what the scene refused, and tracing is undefined
  /// until they are mended and this is called again. Throws for a mesh the scene owns.
  void vertices_changed(uint32_t mesh);
  /// True when mesh i's arrays are the caller's (add_shared_mesh, add_shared_instanced_mesh).
  bool is_shared(size_t i) const { return meshes_.shared[i] != 0; }
  /// Places instanced mesh `mesh` by `object_to_world`; returns the instance's id (its index
  /// in instances()). Throws rp::Error for a mesh that is not instanced, a transform that is
  /// not finite or not invertible, whose linear part or its inverse stretches by more than
  /// kMaxInstanceScale (largest row sum of |L|), or that puts the mesh's box outside the
  /// coordinate range.
  uint32_t add_instance(uint32_t mesh, const Affine3f& object_to_world);
  /// Appends a sphere; returns its geometry id (geometry_of).
  uint32_t add_sphere(const Sphere& s);
  /// Appends a quadric; returns its geometry id.
  /// The coefficients are stored scaled by a power of two so that the largest |A..J| lies in
  /// [1, 2): the same surface, every computed value scaled exactly, and no overflow for any
  /// valid ray (core/ray.h). The clip box must be finite and within the coordinate range.
  uint32_t add_quadric(const QuadricShape& q);
  /// Polygon from >= 3 coplanar vertices; convexity is detected. Returns its geometry id.
  uint32_t add_polygon(std::span<const Vec3f> vertices, uint32_t material);
  /// Appends an unbounded plane; returns its geometry id.
  uint32_t add_plane(const Plane& p);
  /// Throws rp::Error for a position outside the coordinate range (rp::in_coordinate_range) or
  /// a negative or non-finite intensity.
  void add_light(const PointLight& l);
  /// Throws rp::Error for a direction that is not finite and non-zero.
  void add_light(const DirectionalLight& l);
  /// Replaces point light i (as add_light checks it). Lights are not in any backend's
  /// structure: no version changes.
  void set_light(uint32_t i, const PointLight& l);
  /// Replaces directional light i (as add_light checks it).
  void set_light(uint32_t i, const DirectionalLight& l);
  void set_camera(const CameraDesc& c) { camera_ = c; }
  /// The axis that points up in the scene's world (0 x, 1 y, 2 z): where a camera that frames
  /// a scene without one stands and where default lights go (up_frame). Y unless a file or
  /// `--up-axis` says otherwise (a glTF is Y up by definition). Throws rp::Error outside 0..2.
  void set_up_axis(int axis);
  int up_axis() const { return up_axis_; }

  /// Changes (docs/updates.md). Each checks its arguments as the add_* calls do and throws
  /// rp::Error naming the object before changing anything. Every change of what a backend
  /// traces raises version(); a backend built or updated at an older version refuses to trace
  /// (rp::Error naming the change) until Backend::update() brings it up to date. Changing a
  /// scene while any thread traces a backend over it, or updates one, is a data race.
  ///
  /// New positions for mesh i's vertices (as many as it has; same triangles). `normals`, when
  /// not empty, replaces the vertex normals too (as many; a mesh without normals takes none);
  /// empty keeps the stored ones. The boxes of the instances that place the mesh follow.
  /// A shared mesh's buffers are the caller's to write: set_vertices refuses it
  /// (vertices_changed).
  void set_vertices(uint32_t mesh, std::span<const Vec3f> positions, std::span<const Vec3f> normals = {});
  /// A new object_to_world for instance i, checked as add_instance checks it.
  void set_transform(uint32_t instance, const Affine3f& object_to_world);
  /// Removes mesh i: later meshes' indices, and their triangles' prim_ids, move down (as do the
  /// ids of every sphere, quadric, polygon and plane); instances keep placing the same meshes.
  /// Throws rp::Error when an instance still places the mesh.
  void remove_mesh(uint32_t mesh);
  /// Removes instance i; later instances' ids move down by one.
  void remove_instance(uint32_t instance);
  /// Remove one analytic primitive or plane: later ones of every kind move down by one id.
  void remove_sphere(uint32_t i);
  void remove_quadric(uint32_t i);
  void remove_polygon(uint32_t i);
  void remove_plane(uint32_t i);

  /// Geometries (Embree's geomID, Open3D's geometry ids): every mesh, sphere, quadric, polygon
  /// and plane is one geometry, numbered in the order they were added (0, 1, ...); removing one
  /// moves the later ones down by one. A triangle of an instanced mesh belongs to its mesh's
  /// geometry in every placement (Hit::instance_id names the placement).
  uint32_t geometry_count() const { return uint32_t(geometries_.size()); }
  /// The geometry of primitive prim_id (< prim_count()).
  uint32_t geometry_of(uint32_t prim_id) const;
  /// The geometry of mesh i.
  uint32_t mesh_geometry(uint32_t mesh) const { return mesh_geometry_[mesh]; }
  /// What geometry g is: its kind and its index among the shapes of that kind (the mesh index
  /// for triangles).
  PrimLocation geometry(uint32_t g) const { return geometries_[g]; }
  /// Sets geometry g's mask (Embree's rtcSetGeometryMask): a ray of mask m sees the geometry
  /// only when (m & mask) != 0 (TraceOptions::masks, core/queries.h). Every geometry starts
  /// with 0xffffffff. Masks are read while tracing, as lights are, so no backend needs an
  /// update; as any change, it must not overlap a trace. Throws rp::Error for a geometry out of
  /// range.
  void set_mask(uint32_t g, uint32_t mask);
  uint32_t mask(uint32_t g) const { return masks_[g]; }
  /// True when some geometry's mask is not 0xffffffff.
  bool has_masks() const { return masked_ != 0; }

  /// Raised by every change of the geometry (an add_*, set_vertices, set_transform, remove_*):
  /// the scene a backend at this version traced. Starts at 0.
  uint64_t version() const { return version_; }
  /// The version at the last change of which primitives exist or of their numbering: any mesh,
  /// sphere, quadric or polygon added or removed (planes are numbered last and traced beside
  /// every structure, so a plane changes version() only).
  uint64_t layout_version() const { return layout_version_; }
  /// The version at the last instance added, removed or moved (set_transform).
  uint64_t instances_version() const { return instances_version_; }
  /// The version at which mesh i's vertices last changed (set_vertices), or it was added.
  uint64_t mesh_version(size_t i) const { return mesh_version_[i]; }
  /// Mesh i's identity: a number no other mesh of this scene has had or will have, kept
  /// while other meshes come and go (a backend keeps the trees of meshes it already built).
  uint64_t mesh_uid(size_t i) const { return mesh_uid_[i]; }
  /// What the last change was, e.g. "mesh 3 has new vertices" ("" at version 0).
  std::string last_change() const;

  const std::vector<Material>& materials() const { return materials_; }
  const std::vector<MeshView>& meshes() const { return meshes_.views; }
  const std::vector<Sphere>& spheres() const { return spheres_; }
  const std::vector<QuadricShape>& quadrics() const { return quadrics_; }
  const std::vector<PolygonShape>& polygons() const { return polygons_; }
  const std::vector<Vec3f>& polygon_vertices() const { return polygon_vertices_; }
  const std::vector<Plane>& planes() const { return planes_; }
  const std::vector<PointLight>& point_lights() const { return point_lights_; }
  const std::vector<DirectionalLight>& directional_lights() const { return directional_lights_; }
  const std::optional<CameraDesc>& camera() const { return camera_; }
  const std::vector<Instance>& instances() const { return instances_; }
  /// True when mesh i is an instanced mesh (add_instanced_mesh).
  bool is_instanced(size_t i) const { return instanced_[i] != 0; }
  /// Bounds of mesh i's vertices in its own coordinates (world coordinates for a world mesh).
  const Box3f& mesh_bounds(size_t i) const { return mesh_bounds_[i]; }

  /// Triangles stored, each once (world and instanced meshes): the flat numbering's share.
  uint32_t triangle_count() const { return triangle_count_; }
  /// Triangles the instances place, counting each placement (0 without instances).
  uint64_t instanced_triangle_count() const { return instanced_triangle_count_; }
  /// First prim_id of mesh i's triangles.
  uint32_t mesh_base(size_t i) const { return mesh_base_[i]; }
  uint32_t sphere_base() const { return triangle_count_; }
  uint32_t quadric_base() const { return sphere_base() + uint32_t(spheres_.size()); }
  uint32_t polygon_base() const { return quadric_base() + uint32_t(quadrics_.size()); }
  uint32_t plane_base() const { return polygon_base() + uint32_t(polygons_.size()); }
  uint32_t prim_count() const { return plane_base() + uint32_t(planes_.size()); }

  /// Kind and index of prim_id (< prim_count()).
  PrimLocation locate(uint32_t prim_id) const {
    if (prim_id < triangle_count_) return locate_triangle(prim_id);
    if (prim_id < quadric_base()) return {PrimKind::sphere, prim_id - sphere_base(), 0};
    if (prim_id < polygon_base()) return {PrimKind::quadric, prim_id - quadric_base(), 0};
    if (prim_id < plane_base()) return {PrimKind::polygon, prim_id - polygon_base(), 0};
    return {PrimKind::plane, prim_id - plane_base(), 0};
  }
  /// Bounds of every bounded primitive in the world (world meshes, instances' boxes, analytic
  /// primitives; planes excluded); empty box for an empty scene.
  Box3f bounds() const;
  /// Bounds of a sphere, quadric (its clip box) or polygon; prim_id in [sphere_base(), plane_base()).
  Box3f prim_bounds(uint32_t prim_id) const;
  /// Closest hit of `ray` with one sphere, quadric or polygon, by the core/geometry/ routine
  /// both backends share (the stable sphere quadratic, the centred quadric, the polygon test).
  Intersection<float> intersect_analytic(uint32_t prim_id, const Ray& ray) const;
  /// The point of sphere or polygon prim_id closest to p (a closest-point query, core/queries.h):
  /// point, distance, u, v (a sphere's surface parameters; 0 for a polygon), prim_id.
  ClosestPoint closest_on_analytic(uint32_t prim_id, const Vec3f& p) const;
  /// Lets the unbounded planes, which live beside every backend's structure, take `hit`
  /// when one is at least as close (t in [tnear, min(tfar, hit.t)]); planes in index order.
  /// Inline so that the per-ray call costs nothing in a scene without planes.
  void intersect_planes(const Ray& ray, Hit& hit) const {
    if (!planes_.empty()) intersect_planes_in_order(ray, hit);
  }
  /// True when any plane is hit within [tnear, tfar].
  bool occluded_by_planes(const Ray& ray) const { return !planes_.empty() && occluded_by_any_plane(ray); }
  /// Position, normals and material of a hit of `ray` (hit.hit() must be true), in world
  /// space: an instance's hit is found in object space (the object ray's barycentric point,
  /// the normals there) and mapped by the instance (normals by the inverse transpose, times
  /// Instance::orientation). The geometric normal is always unit length: where rounding leaves
  /// no direction (a point computed at a tiny shape's centre from far away), it is
  /// -normalize(ray.dir).
  SurfacePoint surface(const Ray& ray, const Hit& hit) const;
  /// Number of triangles with zero area (kept: they never produce hits).
  size_t degenerate_triangle_count() const;
  /// Bytes held by the scene's arrays (capacity excluded; what the model needs); a shared
  /// mesh's buffers are the caller's and not counted.
  size_t bytes() const;

 private:
  /// locate() of a triangle's id: its mesh by binary search over the mesh bases.
  PrimLocation locate_triangle(uint32_t prim_id) const;
  SurfacePoint instance_surface(const Ray& ray, const Hit& hit) const;  ///< surface of an instance's hit
  void intersect_planes_in_order(const Ray& ray, Hit& hit) const;
  bool occluded_by_any_plane(const Ray& ray) const;
  /// The instance placing `mesh` by `object_to_world`, checked (add_instance); `what` names it.
  Instance placement(uint32_t mesh, const Affine3f& object_to_world, const std::string& what) const;
  /// A change as last_change() tells it: what happened to which object.
  enum class Change : uint8_t { none, added, removed, vertices, transform };
  enum class Object : uint8_t { mesh, instance, sphere, quadric, polygon, plane };
  /// Records a change: version() + 1; `layout`, `instances` raise those versions too.
  void changed(Change change, Object object, uint32_t index, bool layout, bool instances);
  /// Numbers a new shape of `kind` (index `index` of its kind) as the next geometry.
  uint32_t add_geometry(PrimKind kind, uint32_t index);
  /// Removes the geometry of shape `index` of `kind`: later geometries move down by one, and
  /// so do the later shapes of that kind.
  void remove_geometry(PrimKind kind, uint32_t index);

  /// The meshes' views and the arrays of those the scene owns. A copy of the scene points its
  /// views at its own copies of the owned arrays (shared meshes stay the caller's).
  struct MeshStore {
    std::vector<MeshView> views;
    std::vector<TriangleMesh> owned;  ///< per mesh; empty for a shared mesh
    std::vector<uint8_t> shared;      ///< per mesh

    MeshStore() = default;
    MeshStore(const MeshStore& o);
    MeshStore& operator=(const MeshStore& o);
    MeshStore(MeshStore&&) = default;  // moving a vector keeps its items where they are
    MeshStore& operator=(MeshStore&&) = default;
    /// Points mesh i's views at owned[i] (which a change of its arrays, or a copy, moved).
    void view_owned(size_t i);
    void erase(size_t i);
    size_t size() const { return views.size(); }
    const MeshView& operator[](size_t i) const { return views[i]; }
  };
  /// Checks a mesh (either kind) and appends it; `owned` is its storage (empty when shared).
  uint32_t append_mesh(const MeshView& mesh, TriangleMesh owned, bool shared, bool instanced);
  /// Checks `positions` and `normals` as new vertices of mesh i, the boxes of the instances
  /// that place it included, and returns the mesh's new box; throws before anything changes.
  Box3f checked_vertices(uint32_t mesh, Strided<Vec3f> positions, Strided<Vec3f> normals,
                         std::vector<std::pair<uint32_t, Box3f>>& moved) const;
  /// Records new vertices of mesh i with box `box` (set_vertices, vertices_changed).
  void vertices_moved(uint32_t mesh, const Box3f& box, const std::vector<std::pair<uint32_t, Box3f>>& moved);

  std::vector<Material> materials_;
  MeshStore meshes_;
  std::vector<uint32_t> mesh_base_;
  std::vector<uint8_t> instanced_;  ///< per mesh: placed only by instances
  std::vector<Box3f> mesh_bounds_;  ///< per mesh, in its own coordinates
  std::vector<uint64_t> mesh_version_, mesh_uid_;  ///< per mesh (mesh_version, mesh_uid)
  uint64_t next_uid_ = 0;
  uint64_t version_ = 0, layout_version_ = 0, instances_version_ = 0;
  Change last_change_ = Change::none;
  Object last_object_ = Object::mesh;
  uint32_t last_index_ = 0;
  std::vector<Instance> instances_;
  uint64_t instanced_triangle_count_ = 0;
  std::vector<PrimLocation> geometries_;  ///< geometry id -> kind and index of its kind
  std::vector<uint32_t> masks_;           ///< per geometry
  uint32_t masked_ = 0;                   ///< geometries whose mask is not 0xffffffff
  /// Per kind (triangle: per mesh), the geometry id of each shape, indexed by PrimKind.
  std::vector<uint32_t> mesh_geometry_, sphere_geometry_, quadric_geometry_, polygon_geometry_, plane_geometry_;
  std::vector<uint32_t>& geometry_ids(PrimKind kind);
  std::vector<Sphere> spheres_;
  std::vector<QuadricShape> quadrics_;
  std::vector<PolygonShape> polygons_;
  std::vector<Vec3f> polygon_vertices_;
  std::vector<Plane> planes_;
  std::vector<PointLight> point_lights_;
  std::vector<DirectionalLight> directional_lights_;
  std::optional<CameraDesc> camera_;
  int up_axis_ = 1;
  uint32_t triangle_count_ = 0;
};

/// Calls f(hit) for the hits of analytic primitive `id` along `r` within [tnear, tfar] in
/// order of t (a sphere or quadric may be crossed twice), until f returns true: for_each_root
/// over Scene::intersect_analytic.
template <class F>
bool for_each_analytic_hit(const Scene& scene, uint32_t id, const Ray& r, uint32_t inst, F&& f) {
  const auto test = [&](const Ray& rest) { return scene.intersect_analytic(id, rest); };
  return for_each_root(r, test, [&](const Intersection<float>& h) { return f(Hit{h.t, id, h.u, h.v, inst}); });
}

/// The embedded default scene: a procedural torus-knot mesh (>= 50k triangles), spheres,
/// several quadrics, a non-convex polygon, a ground plane, a point and a directional light.
Scene make_default_scene();

}  // namespace rp
