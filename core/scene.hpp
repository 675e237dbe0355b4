#pragma once
/// @file
/// A scene (docs/DESIGN.md §1 "Scenes"): objects with their own topology, kind and self-collision flag, the object
/// pairs that may collide, and the thickness δ. Positions are not part of it: they come per step (step.hpp).

#include "core/shape.hpp"
#include "core/topology.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ccd {

/// deformable: free per-vertex motion. rigid: the data moves it as one body (recorded, not exploited yet).
/// static_object: identical positions in every frame; its hierarchy is built once and never refitted.
/// shape: an analytic convex obstacle (core/shape.hpp): no faces, one vertex, its centre, moved by a motion track.
enum class ObjectKind { deformable, rigid, static_object, shape };

std::string_view to_string(ObjectKind kind);
/// "deformable", "rigid", "static" or "shape"; nullopt otherwise.
std::optional<ObjectKind> parse_object_kind(std::string_view text);

/// What a scene is built from: one object with its local topology (vertex ids 0..num_vertices-1).
struct ObjectDescription {
  std::string name;
  ObjectKind kind = ObjectKind::deformable;
  bool self_collision = true;
  std::size_t num_vertices = 0;
  std::vector<Face> faces;
  /// Kind shape only (then num_vertices is 1, the centre, and faces is empty).
  std::optional<Shape> shape = std::nullopt;
};

/// An object inside a scene: its ranges in the scene's global vertex and face numbering.
struct SceneObject {
  std::string name;
  ObjectKind kind;
  bool self_collision;
  VertexId first_vertex;
  std::size_t num_vertices;
  FaceId first_face;
  std::size_t num_faces;
  /// Kind shape only: its size; its centre is vertex first_vertex of each frame (unused by any face, so never a
  /// primitive of a VF or EE pair).
  std::optional<Shape> shape;
};

/// Objects concatenated into one global numbering, in declaration order: object i's vertices follow those of
/// objects 0..i-1, and likewise its faces. Pair ids (pair_id.hpp) use the global numbering.
class Scene {
 public:
  /// @param collidable  unordered pairs of distinct object indices that may collide with each other
  /// @param thickness   δ >= 0, finite (docs/DESIGN.md §1)
  /// @throws InputError on an empty or duplicate name, a bad face list (named by object and face), a collidable
  ///         pair naming a missing object or one object twice, a negative or non-finite thickness, or a shape object
  ///         without a valid shape, with other than one vertex, with faces or with self-collision.
  Scene(std::vector<ObjectDescription> objects, std::vector<std::pair<ObjectId, ObjectId>> collidable, double thickness);

  const std::vector<SceneObject>& objects() const { return objects_; }
  const SceneObject& object(ObjectId id) const { return objects_[id]; }
  std::optional<ObjectId> find_object(std::string_view name) const;
  /// The global mesh: all objects' faces with global vertex ids.
  const MeshTopology& topology() const { return topology_; }
  double thickness() const { return thickness_; }
  /// Sorted (a < b) object pairs that may collide with each other.
  const std::vector<std::pair<ObjectId, ObjectId>>& collidable_pairs() const { return collidable_; }

  /// Objects of kind shape, ascending.
  const std::vector<ObjectId>& shape_objects() const { return shape_objects_; }

  /// Whether primitives of objects a and b may collide: a == b asks for a's self-collision flag.
  bool may_collide(ObjectId a, ObjectId b) const;
  ObjectId object_of_vertex(VertexId v) const;
  ObjectId object_of_face(FaceId f) const;

  /// The same scene with another thickness (for --thickness).
  Scene with_thickness(double thickness) const;

 private:
  std::vector<SceneObject> objects_;
  std::vector<std::pair<ObjectId, ObjectId>> collidable_;
  std::vector<ObjectId> shape_objects_;
  MeshTopology topology_;
  double thickness_ = 0.0;
};

}  // namespace ccd
