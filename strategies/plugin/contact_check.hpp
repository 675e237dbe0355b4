#pragma once
/// @file
/// The checks every contact made outside ccdbench passes before it counts (a whole-step plugin's, an answer file's):
/// its indices are in range, its two primitives share no vertex, the scene lets their objects collide, an edge is
/// one of the mesh's, a TOI is a number in [0, 1], and no pair comes twice. What fails is the producer's error, never
/// an answer.

#include "core/collision_set.hpp"
#include "core/scene.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_set>

namespace ccd::plugin {

/// Contacts made outside ccdbench name mesh primitives only: `name` cannot run a scene with analytic shapes.
/// @throws std::invalid_argument "NAME: WHY; scene object 'X' is one" when `scene` has one.
void refuse_shapes(const std::string& name, const Scene& scene, const std::string& why);

class ContactCheck {
 public:
  /// What a contact's TOI may be: required (a plugin that reports TOIs), optional (an answer file: NaN is "none"),
  /// ignored (a plugin that reports none: whatever it wrote there is not an answer).
  enum class Toi { required, optional, ignored };
  ContactCheck(const Scene& scene, Toi toi) : scene_(scene), toi_(toi) {}

  /// Starts a step: forgets the pairs seen.
  void reset();
  /// The pair as ccdbench names it, or why it is refused. A TOI that is not an answer becomes kNoToi.
  std::optional<VertexFacePair> vertex_face(std::uint64_t v, std::uint64_t f, double& toi, std::string& why);
  std::optional<EdgeEdgePair> edge_edge(std::uint64_t a0, std::uint64_t a1, std::uint64_t b0, std::uint64_t b1, double& toi, std::string& why);

 private:
  bool check_toi(double& toi, std::string& why) const;
  const Scene& scene_;
  Toi toi_;
  std::unordered_set<VertexFacePair> vertex_face_;
  std::unordered_set<EdgeEdgePair> edge_edge_;
};

}  // namespace ccd::plugin
