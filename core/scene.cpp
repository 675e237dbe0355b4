#include "core/scene.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace ccd {

std::string_view to_string(ObjectKind kind) {
  switch (kind) {
    case ObjectKind::deformable: return "deformable";
    case ObjectKind::rigid: return "rigid";
    case ObjectKind::static_object: return "static";
    case ObjectKind::shape: return "shape";
  }
  return "?";
}

std::optional<ObjectKind> parse_object_kind(std::string_view text) {
  for (ObjectKind kind : {ObjectKind::deformable, ObjectKind::rigid, ObjectKind::static_object, ObjectKind::shape}) {
    if (text == to_string(kind)) return kind;
  }
  return std::nullopt;
}

namespace {

/// δ must be finite and >= 0 (docs/DESIGN.md §1).
void check_thickness(double thickness) {
  if (!std::isfinite(thickness) || thickness < 0.0) {
    throw InputError({}, "thickness", "must be finite and >= 0, got " + std::to_string(thickness));
  }
}

/// A shape object is its shape and its centre: one vertex, no faces, no self-collision; other objects have no shape.
void check_shape_object(const ObjectDescription& object) {
  const std::string where = "object '" + object.name + "'";
  if (object.kind != ObjectKind::shape) {
    if (object.shape) throw InputError({}, where, "only an object of kind shape has a shape");
    return;
  }
  if (!object.shape) throw InputError({}, where, "an object of kind shape needs a shape (sphere or box)");
  if (auto problem = find_shape_problem(*object.shape)) throw InputError({}, where, *problem);
  if (object.num_vertices != 1 || !object.faces.empty()) {
    throw InputError({}, where, "a shape object's frames hold its centre only (one vertex, no faces)");
  }
  if (object.self_collision) throw InputError({}, where, "a shape has no self-collision");
}

}  // namespace

Scene::Scene(std::vector<ObjectDescription> objects, std::vector<std::pair<ObjectId, ObjectId>> collidable, double thickness)
    : thickness_(thickness) {
  check_thickness(thickness);
  std::vector<Face> global_faces;
  std::size_t num_vertices = 0;
  for (ObjectDescription& object : objects) {
    if (object.name.empty()) throw InputError({}, "objects", "an object has an empty name");
    if (find_object(object.name)) throw InputError({}, "objects", "duplicate object name '" + object.name + "'");
    if (auto problem = find_face_list_problem(object.num_vertices, object.faces)) {
      throw InputError({}, "object '" + object.name + "', face " + std::to_string(problem->face), problem->reason);
    }
    check_shape_object(object);
    if (object.kind == ObjectKind::shape) shape_objects_.push_back(static_cast<ObjectId>(objects_.size()));
    objects_.push_back(SceneObject{object.name, object.kind, object.self_collision, static_cast<VertexId>(num_vertices), object.num_vertices,
                                   static_cast<FaceId>(global_faces.size()), object.faces.size(), object.shape});
    for (const Face& face : object.faces) {
      const auto offset = static_cast<VertexId>(num_vertices);
      global_faces.push_back({face[0] + offset, face[1] + offset, face[2] + offset});
    }
    num_vertices += object.num_vertices;
  }
  for (auto [a, b] : collidable) {
    if (a >= objects_.size() || b >= objects_.size()) {
      throw InputError({}, "collidable", "object index out of range");
    }
    if (a == b) {
      throw InputError({}, "collidable", "object '" + objects_[a].name + "' is paired with itself: use its self_collision flag instead");
    }
    collidable_.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(collidable_.begin(), collidable_.end());
  collidable_.erase(std::unique(collidable_.begin(), collidable_.end()), collidable_.end());
  topology_ = MeshTopology(num_vertices, std::move(global_faces));
}

std::optional<ObjectId> Scene::find_object(std::string_view name) const {
  for (ObjectId id = 0; id < objects_.size(); ++id) {
    if (objects_[id].name == name) return id;
  }
  return std::nullopt;
}

bool Scene::may_collide(ObjectId a, ObjectId b) const {
  if (a == b) return objects_[a].self_collision;
  return std::binary_search(collidable_.begin(), collidable_.end(), std::pair{std::min(a, b), std::max(a, b)});
}

ObjectId Scene::object_of_vertex(VertexId v) const {
  const auto it = std::upper_bound(objects_.begin(), objects_.end(), v, [](VertexId x, const SceneObject& o) { return x < o.first_vertex; });
  return static_cast<ObjectId>((it - objects_.begin()) - 1);
}

ObjectId Scene::object_of_face(FaceId f) const {
  const auto it = std::upper_bound(objects_.begin(), objects_.end(), f, [](FaceId x, const SceneObject& o) { return x < o.first_face; });
  return static_cast<ObjectId>((it - objects_.begin()) - 1);
}

Scene Scene::with_thickness(double thickness) const {
  check_thickness(thickness);
  Scene copy = *this;
  copy.thickness_ = thickness;
  return copy;
}

}  // namespace ccd
