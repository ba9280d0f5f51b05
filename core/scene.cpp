#include "core/scene.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "core/geometry/closest_point.h"
#include "core/geometry/plane.h"
#include "core/geometry/sphere.h"
#include "core/surface_lanes.h"

namespace rp {

const char* to_string(PrimKind k) {
  switch (k) {
    case PrimKind::triangle: return "triangle";
    case PrimKind::sphere: return "sphere";
    case PrimKind::quadric: return "quadric";
    case PrimKind::polygon: return "polygon";
    case PrimKind::plane: return "plane";
  }
  return "?";
}

UpFrame up_frame(int axis) {
  switch (axis) {
    case 0: return {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}};
    case 2: return {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}};
    default: return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  }
}

void Scene::set_up_axis(int axis) {
  RP_CHECK(axis >= 0 && axis <= 2, "up axis ", axis, " is not 0 (x), 1 (y) or 2 (z)");
  up_axis_ = axis;
}

uint32_t Scene::add_material(Material m) {
  RP_CHECK(m.ior >= 1.0f && std::isfinite(m.ior), "material '", m.name, "': ior ", m.ior, " must be >= 1");
  RP_CHECK(m.shininess >= 0.0f && std::isfinite(m.shininess), "material '", m.name, "': shininess ",
           m.shininess, " must be >= 0");
  materials_.push_back(std::move(m));
  return uint32_t(materials_.size() - 1);
}

/// "(x, y, z)" for messages.
static std::string show(const Vec3f& v) { return cat("(", v.x, ", ", v.y, ", ", v.z, ")"); }

/// The coordinate range as messages state it.
static const char* const kRangeText = "the supported coordinate range |x| <= 1073741824 (2^30)";

static void check_material(const std::vector<Material>& materials, uint32_t id, const std::string& what) {
  RP_CHECK(id < materials.size(), what, ": material index ", id, " out of range (", materials.size(),
           " materials)");
}

/// The image of `box` under `m`: its 8 corners mapped in double, rounded outward (empty
/// stays empty).
static Box3f placed_box(const Box3f& box, const Affine3f& object_to_world) {
  if (box.empty()) return box;
  const Affine3d m(object_to_world);
  Box3d image;
  for (int c = 0; c < 8; ++c)
    image.extend(
        m.point(Vec3d((c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y, (c & 4) ? box.hi.z : box.lo.z)));
  return outward(image);
}

/// Checks that every position is finite and within the coordinate range; `what` names the mesh.
static void check_positions(Strided<Vec3f> positions, const std::string& what) {
  for (size_t i = 0; i < positions.size(); ++i) {
    RP_CHECK(is_finite(positions[i]), what, ": vertex ", i, " has a non-finite coordinate");
    RP_CHECK(in_coordinate_range(positions[i]), what, ": vertex ", i, " ", show(positions[i]), " is outside ",
             kRangeText);
  }
}

/// The box of the vertices the triangles use.
static Box3f used_bounds(Strided<Vec3f> positions, Strided<TriangleIndices> triangles) {
  Box3f box;
  for (const TriangleIndices& t : triangles)
    for (uint32_t i : t) box.extend(positions[i]);
  return box;
}

/// The views of a TriangleMesh's arrays (its index count a multiple of 3).
static MeshView view_of(const TriangleMesh& m) {
  return {m.name,
          m.positions,
          Strided<TriangleIndices>(reinterpret_cast<const TriangleIndices*>(m.indices.data()), m.indices.size() / 3),
          m.normals,
          m.uvs,
          m.face_materials,
          m.material};
}

TriangleMesh to_triangle_mesh(const MeshView& m) {
  TriangleMesh out;
  out.name = m.name;
  out.material = m.material;
  out.positions.assign(m.positions.begin(), m.positions.end());
  out.indices.reserve(3 * size_t(m.triangle_count()));
  for (const TriangleIndices& t : m.triangles) out.indices.insert(out.indices.end(), t.begin(), t.end());
  out.normals.assign(m.normals.begin(), m.normals.end());
  out.uvs.assign(m.uvs.begin(), m.uvs.end());
  out.face_materials.assign(m.face_materials.begin(), m.face_materials.end());
  return out;
}

Scene::MeshStore::MeshStore(const MeshStore& o) : views(o.views), owned(o.owned), shared(o.shared) {
  for (size_t i = 0; i < views.size(); ++i)
    if (!shared[i]) view_owned(i);
}

Scene::MeshStore& Scene::MeshStore::operator=(const MeshStore& o) {
  if (this != &o) *this = MeshStore(o);
  return *this;
}

void Scene::MeshStore::view_owned(size_t i) { views[i] = view_of(owned[i]); }

void Scene::MeshStore::erase(size_t i) {
  views.erase(views.begin() + ptrdiff_t(i));
  owned.erase(owned.begin() + ptrdiff_t(i));
  shared.erase(shared.begin() + ptrdiff_t(i));
}

uint32_t Scene::add_mesh(TriangleMesh mesh) {
  RP_CHECK(mesh.indices.size() % 3 == 0, "mesh '", mesh.name, "': index count ", mesh.indices.size(),
           " is not a multiple of 3");
  const MeshView view = view_of(mesh);
  return append_mesh(view, std::move(mesh), false, false);
}

uint32_t Scene::add_instanced_mesh(TriangleMesh mesh) {
  RP_CHECK(mesh.indices.size() % 3 == 0, "mesh '", mesh.name, "': index count ", mesh.indices.size(),
           " is not a multiple of 3");
  const MeshView view = view_of(mesh);
  return append_mesh(view, std::move(mesh), false, true);
}

uint32_t Scene::add_shared_mesh(const MeshView& mesh) { return append_mesh(mesh, {}, true, false); }

uint32_t Scene::add_shared_instanced_mesh(const MeshView& mesh) { return append_mesh(mesh, {}, true, true); }

/// Checks that `view`'s items can be read (Strided::fits); `what` names the mesh, `array` the view.
template <typename T>
static void check_layout(const Strided<T>& view, const std::string& what, const char* array) {
  RP_CHECK(view.fits(), what, ": the ", array, " buffer (", view.size(), " items at ",
           static_cast<const void*>(view.data()), ", stride ", view.stride(), " bytes) needs a non-null start and ",
           "stride aligned to ", alignof(T), " bytes and a stride of at least ", sizeof(T));
}

uint32_t Scene::append_mesh(const MeshView& mesh, TriangleMesh owned, bool shared, bool instanced) {
  const std::string what = "mesh '" + mesh.name + "'";
  check_layout(mesh.positions, what, "positions");
  check_layout(mesh.triangles, what, "triangles");
  check_layout(mesh.normals, what, "normals");
  check_layout(mesh.uvs, what, "uvs");
  check_layout(mesh.face_materials, what, "face materials");
  const size_t nv = mesh.positions.size();
  check_positions(mesh.positions, what);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (uint32_t i : mesh.triangles[t]) RP_CHECK(i < nv, what, ": triangle ", t, " uses vertex ", i, " of ", nv);
  RP_CHECK(mesh.normals.empty() || mesh.normals.size() == nv, what, ": ", mesh.normals.size(),
           " normals for ", nv, " vertices");
  RP_CHECK(mesh.uvs.empty() || mesh.uvs.size() == nv, what, ": ", mesh.uvs.size(), " uvs for ", nv, " vertices");
  for (size_t i = 0; i < mesh.normals.size(); ++i)
    RP_CHECK(is_finite(mesh.normals[i]), what, ": normal ", i, " has a non-finite coordinate");
  RP_CHECK(mesh.face_materials.empty() || mesh.face_materials.size() == mesh.triangles.size(), what, ": ",
           mesh.face_materials.size(), " face materials for ", mesh.triangles.size(), " triangles");
  check_material(materials_, mesh.material, what);
  for (uint32_t m : mesh.face_materials) check_material(materials_, m, what);
  RP_CHECK(uint64_t(triangle_count_) + mesh.triangles.size() < uint64_t(kInvalidId) / 2, what, ": scene exceeds ",
           kInvalidId / 2, " triangles");
  const Box3f box = used_bounds(mesh.positions, mesh.triangles);
  mesh_base_.push_back(triangle_count_);
  instanced_.push_back(uint8_t(instanced));
  mesh_bounds_.push_back(box);
  triangle_count_ += mesh.triangle_count();
  meshes_.views.push_back(mesh);
  meshes_.owned.push_back(std::move(owned));
  meshes_.shared.push_back(uint8_t(shared));
  if (!shared) meshes_.view_owned(meshes_.size() - 1);
  add_geometry(PrimKind::triangle, uint32_t(meshes_.size() - 1));
  changed(Change::added, Object::mesh, uint32_t(meshes_.size() - 1), true, false);
  mesh_version_.push_back(version_);
  mesh_uid_.push_back(next_uid_++);
  return uint32_t(meshes_.size() - 1);
}

Instance Scene::placement(uint32_t mesh, const Affine3f& object_to_world, const std::string& what) const {
  RP_CHECK(mesh < meshes_.size(), what, ": mesh ", mesh, " out of range (", meshes_.size(), " meshes)");
  RP_CHECK(instanced_[mesh], what, ": mesh '", meshes_[mesh].name, "' is a world mesh, not an instanced one");
  RP_CHECK(object_to_world.is_finite(), what, ": the transform of mesh '", meshes_[mesh].name, "' is not finite");
  const std::optional<Affine3f> inv = float_inverse(object_to_world);
  RP_CHECK(inv.has_value(), what, ": the transform of mesh '", meshes_[mesh].name, "' is not invertible");
  const Affine3f& world_to_object = *inv;
  const float stretch = std::max(object_to_world.linear_norm(), world_to_object.linear_norm());
  RP_CHECK(world_to_object.is_finite() && stretch <= kMaxInstanceScale, what, ": the transform of mesh '",
           meshes_[mesh].name, "' stretches by ", stretch, ", beyond ", kMaxInstanceScale, " (2^20) either way");
  Instance in;
  in.mesh = mesh;
  in.object_to_world = object_to_world;
  in.world_to_object = world_to_object;
  in.orientation = object_to_world.determinant() < 0.0f ? -1.0f : 1.0f;
  in.bounds = placed_box(mesh_bounds_[mesh], object_to_world);
  RP_CHECK(in.bounds.empty() || (in_coordinate_range(in.bounds.lo) && in_coordinate_range(in.bounds.hi)), what,
           ": mesh '", meshes_[mesh].name, "' placed at ", show(in.bounds.lo), " - ", show(in.bounds.hi),
           " is outside ", kRangeText);
  return in;
}

uint32_t Scene::add_instance(uint32_t mesh, const Affine3f& object_to_world) {
  const std::string what = cat("instance ", instances_.size());
  const Instance in = placement(mesh, object_to_world, what);
  RP_CHECK(instances_.size() + 1 < size_t(kNoInstance), what, ": too many instances");
  instances_.push_back(in);
  instanced_triangle_count_ += meshes_[mesh].triangle_count();
  changed(Change::added, Object::instance, uint32_t(instances_.size() - 1), false, true);
  return uint32_t(instances_.size() - 1);
}

uint32_t Scene::add_sphere(const Sphere& s) {
  RP_CHECK(is_finite(s.center) && std::isfinite(s.radius) && s.radius > 0.0f, "sphere at ", show(s.center),
           " radius ", s.radius, ": needs a finite centre and radius > 0");
  RP_CHECK(in_coordinate_range(s.center - Vec3f(s.radius)) && in_coordinate_range(s.center + Vec3f(s.radius)),
           "sphere at ", show(s.center), " radius ", s.radius, ": its box is outside ", kRangeText);
  check_material(materials_, s.material, "sphere");
  spheres_.push_back(s);
  changed(Change::added, Object::sphere, uint32_t(spheres_.size() - 1), true, false);
  return add_geometry(PrimKind::sphere, uint32_t(spheres_.size() - 1));
}

uint32_t Scene::add_quadric(const QuadricShape& q) {
  const Box3f b = q.quadric.clip;
  RP_CHECK(!b.empty() && is_finite(b.lo) && is_finite(b.hi), "quadric: clipping box must be finite and non-empty");
  RP_CHECK(in_coordinate_range(b.lo) && in_coordinate_range(b.hi) && in_coordinate_range(q.quadric.center),
           "quadric: clipping box ", show(b.lo), " - ", show(b.hi), " or centre ", show(q.quadric.center),
           " is outside ", kRangeText);
  check_material(materials_, q.material, "quadric");
  const Quadricf& c = q.quadric;
  for (float t : {c.A, c.B, c.C, c.D, c.E, c.F, c.G, c.H, c.I, c.J})
    RP_CHECK(std::isfinite(t), "quadric: coefficient ", t, " is not finite");
  QuadricShape scaled = q;
  scaled.quadric = c.normalized();
  quadrics_.push_back(scaled);
  changed(Change::added, Object::quadric, uint32_t(quadrics_.size() - 1), true, false);
  return add_geometry(PrimKind::quadric, uint32_t(quadrics_.size() - 1));
}

uint32_t Scene::add_polygon(std::span<const Vec3f> vertices, uint32_t material) {
  RP_CHECK(vertices.size() >= 3, "polygon: needs at least 3 vertices, got ", vertices.size());
  for (const Vec3f& v : vertices) {
    RP_CHECK(is_finite(v), "polygon: non-finite vertex");
    RP_CHECK(in_coordinate_range(v), "polygon: vertex ", show(v), " is outside ", kRangeText);
  }
  check_material(materials_, material, "polygon");
  PolygonShape p;
  p.first = uint32_t(polygon_vertices_.size());
  p.count = uint32_t(vertices.size());
  p.plane = polygon_plane<float>(vertices);
  RP_CHECK(length(p.plane.n) > 0.0f, "polygon: vertices are collinear (zero area)");
  p.convex = polygon_is_convex<float>(vertices);
  p.material = material;
  polygon_vertices_.insert(polygon_vertices_.end(), vertices.begin(), vertices.end());
  polygons_.push_back(p);
  changed(Change::added, Object::polygon, uint32_t(polygons_.size() - 1), true, false);
  return add_geometry(PrimKind::polygon, uint32_t(polygons_.size() - 1));
}

uint32_t Scene::add_plane(const Plane& p) {
  RP_CHECK(is_finite(p.normal) && length(p.normal) > 0.0f && std::isfinite(p.d),
           "plane: needs a finite non-zero normal and finite offset");
  RP_CHECK(std::abs(p.d) / length(p.normal) <= kMaxCoordinate, "plane: its distance from the origin, ",
           std::abs(p.d) / length(p.normal), ", is outside ", kRangeText);
  check_material(materials_, p.material, "plane");
  planes_.push_back(p);
  changed(Change::added, Object::plane, uint32_t(planes_.size() - 1), false, false);
  return add_geometry(PrimKind::plane, uint32_t(planes_.size() - 1));
}

static void check_light(const PointLight& l) {
  RP_CHECK(in_coordinate_range(l.position), "point light at ", show(l.position), ": outside ", kRangeText);
  RP_CHECK(is_finite(l.intensity) && min_component(l.intensity) >= 0.0f, "point light at ", show(l.position),
           ": intensity ", show(l.intensity), " must be finite and >= 0");
}

static void check_light(const DirectionalLight& l) {
  RP_CHECK(is_finite(l.direction) && length(l.direction) > 0.0f, "directional light: direction ", show(l.direction),
           " must be finite and non-zero");
  RP_CHECK(is_finite(l.irradiance) && min_component(l.irradiance) >= 0.0f, "directional light: irradiance ",
           show(l.irradiance), " must be finite and >= 0");
}

void Scene::add_light(const PointLight& l) {
  check_light(l);
  point_lights_.push_back(l);
}

void Scene::add_light(const DirectionalLight& l) {
  check_light(l);
  directional_lights_.push_back(l);
}

void Scene::set_light(uint32_t i, const PointLight& l) {
  RP_CHECK(i < point_lights_.size(), "point light ", i, " out of range (", point_lights_.size(), " point lights)");
  check_light(l);
  point_lights_[i] = l;
}

void Scene::set_light(uint32_t i, const DirectionalLight& l) {
  RP_CHECK(i < directional_lights_.size(), "directional light ", i, " out of range (", directional_lights_.size(),
           " directional lights)");
  check_light(l);
  directional_lights_[i] = l;
}

void Scene::changed(Change change, Object object, uint32_t index, bool layout, bool instances) {
  ++version_;
  if (layout) layout_version_ = version_;
  if (instances) instances_version_ = version_;
  last_change_ = change;
  last_object_ = object;
  last_index_ = index;
}

std::string Scene::last_change() const {
  static constexpr const char* kObject[] = {"mesh", "instance", "sphere", "quadric", "polygon", "plane"};
  const std::string what = cat(kObject[int(last_object_)], " ", last_index_);
  switch (last_change_) {
    case Change::none:
      return "";
    case Change::added:
      return what + " was added";
    case Change::removed:
      return what + " was removed";
    case Change::vertices:
      return what + " has new vertices";
    case Change::transform:
      return what + " has a new transform";
  }
  return "";
}

Box3f Scene::checked_vertices(uint32_t mesh, Strided<Vec3f> positions, Strided<Vec3f> normals,
                              std::vector<std::pair<uint32_t, Box3f>>& moved) const {
  const MeshView& m = meshes_[mesh];
  const std::string what = cat("mesh '", m.name, "' (", mesh, ")");
  RP_CHECK(positions.size() == m.positions.size(), what, ": ", positions.size(), " new positions for ",
           m.positions.size(), " vertices");
  RP_CHECK(normals.empty() || normals.size() == m.normals.size(), what, ": ", normals.size(), " new normals for ",
           m.normals.size(), " stored");
  check_positions(positions, what);
  for (size_t i = 0; i < normals.size(); ++i)
    RP_CHECK(is_finite(normals[i]), what, ": normal ", i, " has a non-finite coordinate");
  // Every instance's new box is checked before anything changes.
  const Box3f box = used_bounds(positions, m.triangles);
  moved.clear();
  for (uint32_t i = 0; i < instances_.size(); ++i) {
    if (instances_[i].mesh != mesh) continue;
    const Box3f b = placed_box(box, instances_[i].object_to_world);
    RP_CHECK(b.empty() || (in_coordinate_range(b.lo) && in_coordinate_range(b.hi)), what, ": instance ", i,
             " would place it at ", show(b.lo), " - ", show(b.hi), ", outside ", kRangeText);
    moved.emplace_back(i, b);
  }
  return box;
}

void Scene::vertices_moved(uint32_t mesh, const Box3f& box, const std::vector<std::pair<uint32_t, Box3f>>& moved) {
  mesh_bounds_[mesh] = box;
  for (const auto& [i, b] : moved) instances_[i].bounds = b;
  changed(Change::vertices, Object::mesh, mesh, false, !moved.empty());
  mesh_version_[mesh] = version_;
}

void Scene::set_vertices(uint32_t mesh, std::span<const Vec3f> positions, std::span<const Vec3f> normals) {
  RP_CHECK(mesh < meshes_.size(), "set_vertices: mesh ", mesh, " out of range (", meshes_.size(), " meshes)");
  RP_CHECK(!meshes_.shared[mesh], "set_vertices: mesh '", meshes_[mesh].name, "' (", mesh,
           ") is in the caller's buffers: write them and call vertices_changed");
  std::vector<std::pair<uint32_t, Box3f>> moved;
  const Box3f box = checked_vertices(mesh, positions, normals, moved);
  TriangleMesh& m = meshes_.owned[mesh];
  m.positions = std::vector<Vec3f>(positions.begin(), positions.end());  // the spans may be the mesh's own
  if (!normals.empty()) m.normals = std::vector<Vec3f>(normals.begin(), normals.end());
  meshes_.view_owned(mesh);
  vertices_moved(mesh, box, moved);
}

void Scene::vertices_changed(uint32_t mesh) {
  RP_CHECK(mesh < meshes_.size(), "vertices_changed: mesh ", mesh, " out of range (", meshes_.size(), " meshes)");
  RP_CHECK(meshes_.shared[mesh], "vertices_changed: mesh '", meshes_[mesh].name, "' (", mesh,
           ") is the scene's own: give it new vertices with set_vertices");
  std::vector<std::pair<uint32_t, Box3f>> moved;
  const MeshView& m = meshes_[mesh];
  const Box3f box = checked_vertices(mesh, m.positions, m.normals, moved);
  vertices_moved(mesh, box, moved);
}

void Scene::set_transform(uint32_t instance, const Affine3f& object_to_world) {
  RP_CHECK(instance < instances_.size(), "set_transform: instance ", instance, " out of range (", instances_.size(),
           " instances)");
  instances_[instance] = placement(instances_[instance].mesh, object_to_world, cat("instance ", instance));
  changed(Change::transform, Object::instance, instance, false, true);
}

void Scene::remove_mesh(uint32_t mesh) {
  RP_CHECK(mesh < meshes_.size(), "remove_mesh: mesh ", mesh, " out of range (", meshes_.size(), " meshes)");
  for (uint32_t i = 0; i < instances_.size(); ++i)
    RP_CHECK(instances_[i].mesh != mesh, "remove_mesh: mesh '", meshes_[mesh].name, "' (", mesh,
             ") is placed by instance ", i, "; remove its instances first");
  const uint32_t n = meshes_[mesh].triangle_count();
  for (size_t m = mesh + 1; m < meshes_.size(); ++m) mesh_base_[m] -= n;
  for (Instance& in : instances_) in.mesh -= in.mesh > mesh;
  meshes_.erase(mesh);
  mesh_base_.erase(mesh_base_.begin() + mesh);
  instanced_.erase(instanced_.begin() + mesh);
  mesh_bounds_.erase(mesh_bounds_.begin() + mesh);
  mesh_version_.erase(mesh_version_.begin() + mesh);
  mesh_uid_.erase(mesh_uid_.begin() + mesh);
  remove_geometry(PrimKind::triangle, mesh);
  triangle_count_ -= n;
  changed(Change::removed, Object::mesh, mesh, true, !instances_.empty());
}

void Scene::remove_instance(uint32_t instance) {
  RP_CHECK(instance < instances_.size(), "remove_instance: instance ", instance, " out of range (", instances_.size(),
           " instances)");
  instanced_triangle_count_ -= meshes_[instances_[instance].mesh].triangle_count();
  instances_.erase(instances_.begin() + instance);
  changed(Change::removed, Object::instance, instance, false, true);
}

void Scene::remove_sphere(uint32_t i) {
  RP_CHECK(i < spheres_.size(), "remove_sphere: sphere ", i, " out of range (", spheres_.size(), " spheres)");
  spheres_.erase(spheres_.begin() + i);
  remove_geometry(PrimKind::sphere, i);
  changed(Change::removed, Object::sphere, i, true, false);
}

void Scene::remove_quadric(uint32_t i) {
  RP_CHECK(i < quadrics_.size(), "remove_quadric: quadric ", i, " out of range (", quadrics_.size(), " quadrics)");
  quadrics_.erase(quadrics_.begin() + i);
  remove_geometry(PrimKind::quadric, i);
  changed(Change::removed, Object::quadric, i, true, false);
}

void Scene::remove_polygon(uint32_t i) {
  RP_CHECK(i < polygons_.size(), "remove_polygon: polygon ", i, " out of range (", polygons_.size(), " polygons)");
  const PolygonShape gone = polygons_[i];
  polygon_vertices_.erase(polygon_vertices_.begin() + gone.first, polygon_vertices_.begin() + gone.first + gone.count);
  polygons_.erase(polygons_.begin() + i);
  remove_geometry(PrimKind::polygon, i);
  for (PolygonShape& p : polygons_) p.first -= p.first > gone.first ? gone.count : 0;
  changed(Change::removed, Object::polygon, i, true, false);
}

void Scene::remove_plane(uint32_t i) {
  RP_CHECK(i < planes_.size(), "remove_plane: plane ", i, " out of range (", planes_.size(), " planes)");
  planes_.erase(planes_.begin() + i);
  remove_geometry(PrimKind::plane, i);
  changed(Change::removed, Object::plane, i, false, false);
}

std::vector<uint32_t>& Scene::geometry_ids(PrimKind kind) {
  switch (kind) {
    case PrimKind::triangle:
      return mesh_geometry_;
    case PrimKind::sphere:
      return sphere_geometry_;
    case PrimKind::quadric:
      return quadric_geometry_;
    case PrimKind::polygon:
      return polygon_geometry_;
    case PrimKind::plane:
      return plane_geometry_;
  }
  return plane_geometry_;
}

uint32_t Scene::add_geometry(PrimKind kind, uint32_t index) {
  const auto g = uint32_t(geometries_.size());
  geometries_.push_back({kind, index, 0});
  masks_.push_back(~0u);
  geometry_ids(kind).push_back(g);
  return g;
}

void Scene::remove_geometry(PrimKind kind, uint32_t index) {
  std::vector<uint32_t>& ids = geometry_ids(kind);
  const uint32_t g = ids[index];
  ids.erase(ids.begin() + index);
  masked_ -= masks_[g] != ~0u;
  geometries_.erase(geometries_.begin() + g);
  masks_.erase(masks_.begin() + g);
  for (PrimLocation& at : geometries_) at.shape -= at.kind == kind && at.shape > index;
  for (std::vector<uint32_t>* v :
       {&mesh_geometry_, &sphere_geometry_, &quadric_geometry_, &polygon_geometry_, &plane_geometry_})
    for (uint32_t& id : *v) id -= id > g;
}

uint32_t Scene::geometry_of(uint32_t prim_id) const {
  const PrimLocation at = locate(prim_id);
  switch (at.kind) {
    case PrimKind::triangle:
      return mesh_geometry_[at.shape];
    case PrimKind::sphere:
      return sphere_geometry_[at.shape];
    case PrimKind::quadric:
      return quadric_geometry_[at.shape];
    case PrimKind::polygon:
      return polygon_geometry_[at.shape];
    case PrimKind::plane:
      return plane_geometry_[at.shape];
  }
  return kInvalidId;
}

void Scene::set_mask(uint32_t g, uint32_t mask) {
  RP_CHECK(g < geometries_.size(), "set_mask: geometry ", g, " out of range (", geometries_.size(), " geometries)");
  masked_ += (mask != ~0u) - (masks_[g] != ~0u);
  masks_[g] = mask;
}

PrimLocation Scene::locate_triangle(uint32_t id) const {
  // The last mesh whose base is <= id.
  auto it = std::upper_bound(mesh_base_.begin(), mesh_base_.end(), id) - 1;
  return {PrimKind::triangle, uint32_t(it - mesh_base_.begin()), id - *it};
}

Box3f Scene::bounds() const {
  Box3f b;
  for (size_t m = 0; m < meshes_.size(); ++m)
    if (!instanced_[m]) b.extend(mesh_bounds_[m]);
  for (const Instance& in : instances_) b.extend(in.bounds);
  for (const Sphere& s : spheres_) b.extend(Box3f(s.center - Vec3f(s.radius), s.center + Vec3f(s.radius)));
  for (const QuadricShape& q : quadrics_) b.extend(q.quadric.clip);
  for (const Vec3f& v : polygon_vertices_) b.extend(v);
  return b;
}

Box3f Scene::prim_bounds(uint32_t id) const {
  const PrimLocation ref = locate(id);
  switch (ref.kind) {
    case PrimKind::sphere: {
      const Sphere& s = spheres_[ref.shape];
      return {s.center - Vec3f(s.radius), s.center + Vec3f(s.radius)};
    }
    case PrimKind::quadric: return quadrics_[ref.shape].quadric.clip;
    case PrimKind::polygon: {
      Box3f b;
      const PolygonShape& p = polygons_[ref.shape];
      for (uint32_t k = 0; k < p.count; ++k) b.extend(polygon_vertices_[p.first + k]);
      return b;
    }
    default: throw Error(cat("prim_bounds: prim ", id, " is a ", to_string(ref.kind), ", not an analytic primitive"));
  }
}

Intersection<float> Scene::intersect_analytic(uint32_t id, const Ray& ray) const {
  const PrimLocation ref = locate(id);
  switch (ref.kind) {
    case PrimKind::sphere: {
      const Sphere& s = spheres_[ref.shape];
      return intersect_sphere_algebraic(ray, s.center, s.radius);
    }
    case PrimKind::quadric: return intersect_quadric(ray, quadrics_[ref.shape].quadric);
    case PrimKind::polygon: {
      const PolygonShape& p = polygons_[ref.shape];
      return intersect_polygon(ray, std::span<const Vec3f>(polygon_vertices_).subspan(p.first, p.count), p.plane,
                               p.convex);
    }
    default: return {};
  }
}

ClosestPoint Scene::closest_on_analytic(uint32_t id, const Vec3f& p) const {
  const PrimLocation ref = locate(id);
  ClosestPoint out;
  out.prim_id = id;
  if (ref.kind == PrimKind::sphere) {
    const Sphere& s = spheres_[ref.shape];
    const Vec3f d = p - s.center;
    const float len = length(d);
    // The centre itself: every point of the sphere is as close; the one on +x.
    out.point = len > 0.0f ? s.center + d * (s.radius / len) : s.center + Vec3f(s.radius, 0.0f, 0.0f);
    const Vec2f uv = sphere_uv(s.center, s.radius, out.point);
    out.u = uv.x;
    out.v = uv.y;
  } else {
    const PolygonShape& g = polygons_[ref.shape];
    out.point = closest_on_polygon(p, std::span<const Vec3f>(polygon_vertices_).subspan(g.first, g.count), g.plane);
  }
  out.distance = length(out.point - p);
  return out;
}

void Scene::intersect_planes_in_order(const Ray& ray, Hit& hit) const {
  for (uint32_t k = 0; k < planes_.size(); ++k) {
    Ray r = ray;
    r.tfar = std::min(ray.tfar, hit.t);
    const Intersection<float> h = intersect_plane(r, planes_[k].normal, planes_[k].d);
    if (h.hit) hit = {h.t, plane_base() + k, h.u, h.v};
  }
}

bool Scene::occluded_by_any_plane(const Ray& ray) const {
  for (const Plane& p : planes_)
    if (intersect_plane(ray, p.normal, p.d).hit) return true;
  return false;
}

// Kept out of line: inside surface, its calls made GCC stop inlining fix_degenerate_normal
// and normalize into the world primitives' path (a measurable share of the default scene's
// shading; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
[[gnu::noinline]] SurfacePoint Scene::instance_surface(const Ray& ray, const Hit& hit) const {
  // The point and normals in the instance's object space, from the object ray, then mapped.
  const Instance& in = instances_[hit.instance_id];
  const SurfacePoint local = surface(object_ray(ray, in.world_to_object), {hit.t, hit.prim_id, hit.u, hit.v});
  PointLanes<float> p = instance_point<float>({local.position, local.geometric_normal, local.shading_normal},
                                              in.object_to_world, in.world_to_object,
                                              in.orientation);
  fix_degenerate_normal<float>(p, ray.org, ray.dir, hit.t);
  return {p.position, p.geometric_normal, p.shading_normal, local.material};
}

SurfacePoint Scene::surface(const Ray& ray, const Hit& hit) const {
  if (hit.instance_id != kNoInstance) return instance_surface(ray, hit);
  SurfacePoint sp;
  const PrimLocation ref = locate(hit.prim_id);
  switch (ref.kind) {
    case PrimKind::triangle: {
      const MeshView& m = meshes_[ref.shape];
      const TriangleIndices& idx = m.triangles[ref.local];
      const Vec3f c[3] = {m.positions[idx[0]], m.positions[idx[1]], m.positions[idx[2]]};
      const bool has_normals = !m.normals.empty();
      const Vec3f n[3] = {has_normals ? m.normals[idx[0]] : Vec3f{}, has_normals ? m.normals[idx[1]] : Vec3f{},
                          has_normals ? m.normals[idx[2]] : Vec3f{}};
      const PointLanes<float> p = triangle_point<float>(c, n, has_normals, hit.u, hit.v);
      sp.position = p.position;
      sp.geometric_normal = p.geometric_normal;
      sp.shading_normal = p.shading_normal;
      sp.material = m.face_materials.empty() ? m.material : m.face_materials[ref.local];
      break;
    }
    case PrimKind::sphere: {
      const Sphere& s = spheres_[ref.shape];
      const PointLanes<float> p = sphere_point<float>(ray.org, ray.dir, hit.t, s.center, s.radius);
      sp.position = p.position;
      sp.geometric_normal = sp.shading_normal = p.geometric_normal;
      sp.material = s.material;
      break;
    }
    case PrimKind::quadric: {
      // One Newton step along the gradient pulls org + t*dir (whose error grows with t)
      // back onto the surface, so that secondary-ray offsets of a few ulps suffice.
      const PointLanes<float> p = quadric_point<float>(ray.org, ray.dir, hit.t, quadrics_[ref.shape].quadric);
      sp.position = p.position;
      sp.geometric_normal = sp.shading_normal = p.geometric_normal;
      sp.material = quadrics_[ref.shape].material;
      break;
    }
    case PrimKind::polygon:
    case PrimKind::plane: {
      const bool polygon = ref.kind == PrimKind::polygon;
      const Vec3f n = polygon ? polygons_[ref.shape].plane.n : planes_[ref.shape].normal;
      const float d = polygon ? polygons_[ref.shape].plane.d : planes_[ref.shape].d;
      const PointLanes<float> p = plane_point<float>(ray.org, ray.dir, hit.t, n, d);
      sp.position = p.position;
      sp.geometric_normal = sp.shading_normal = p.geometric_normal;
      sp.material = polygon ? polygons_[ref.shape].material : planes_[ref.shape].material;
      break;
    }
  }
  // A shape much smaller than the rounding of a far-away hit point (a unit sphere or quadric
  // seen from 2^30 away) can put the computed point at its centre, where the gradient is 0:
  // the normal then faces the ray rather than being zero.
  PointLanes<float> p{sp.position, sp.geometric_normal, sp.shading_normal};
  fix_degenerate_normal<float>(p, ray.org, ray.dir, hit.t);
  sp.position = p.position;
  sp.geometric_normal = p.geometric_normal;
  sp.shading_normal = p.shading_normal;
  return sp;
}

size_t Scene::degenerate_triangle_count() const {
  size_t n = 0;
  for (const MeshView& m : meshes_.views)
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
      Vec3f c = cross(m.vertex(t, 1) - m.vertex(t, 0), m.vertex(t, 2) - m.vertex(t, 0));
      n += (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f);
    }
  return n;
}

size_t Scene::bytes() const {
  size_t b = instances_.size() * sizeof(Instance) + mesh_bounds_.size() * sizeof(Box3f) + instanced_.size();
  for (size_t i = 0; i < meshes_.size(); ++i) {
    const MeshView& m = meshes_[i];
    if (!meshes_.shared[i])
      b += m.positions.size() * sizeof(Vec3f) + m.triangles.size() * sizeof(TriangleIndices) +
           m.normals.size() * sizeof(Vec3f) + m.uvs.size() * sizeof(Vec2f) + m.face_materials.size() * sizeof(uint32_t);
  }
  b += spheres_.size() * sizeof(Sphere) + quadrics_.size() * sizeof(QuadricShape) +
       polygons_.size() * sizeof(PolygonShape) + polygon_vertices_.size() * sizeof(Vec3f) +
       planes_.size() * sizeof(Plane) + mesh_base_.size() * sizeof(uint32_t);
  return b;
}

}  // namespace rp
