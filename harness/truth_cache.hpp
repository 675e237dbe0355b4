#pragma once
/// @file
/// Whole-step truth, computed once per step and kept on disk: keyed by the step's content (positions and
/// topology), δ, the collision filter (self flags, collidable pairs) and a digest of the reference's sources taken
/// at build time (so a change to the reference can never read old truth, and nobody has to remember a version).
/// Each file carries a checksum and every pair is checked against the scene when read; a file that fails either
/// check is reported and recomputed, never used.

#include "core/collision_set.hpp"
#include "core/scene.hpp"
#include "datasets/content_hash.hpp"

#include <filesystem>
#include <iosfwd>
#include <span>
#include <string>

namespace ccd::harness {

/// What the cache key holds of the reference's version: the build-time digest of its sources and CGAL's version.
std::string reference_version();

/// Feeds everything of a scene but its positions and δ to `hash`: topology, objects (name, kind, self-collision
/// flag, numbering) and the collidable pairs. Truth keys and the keys of resumed cells both use it, so that
/// neither can forget a part of the scene that the other covers.
void hash_scene_structure(datasets::ContentHash& hash, const Scene& scene);

/// A 128-bit content key, as 32 hex digits.
std::string truth_key(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1);

/// Writes a truth file: magic, counts, a flags word (1: exact TOIs follow the pairs; 2: a face-shape count follows
/// and face-shape pairs follow the edge-edge ones), the pairs, with_toi the TOI
/// of every pair (the largest double not after the exact earliest contact), and an XXH3-64 checksum of everything
/// before it.
void write_truth_file(const std::filesystem::path& path, const CollisionSet& truth, bool with_toi = false);

struct CachedTruth {
  CollisionSet collisions;
  /// Whether the file holds exact TOIs (then every contact's toi is set).
  bool with_toi = false;
};

/// Reads a truth file for `scene`. The counts must match the file's size before anything is allocated, the
/// checksum must match, and every pair must be one the scene has: vertex and face ids in range, the vertex used and
/// not a corner of the face, both edges of the mesh and sharing no vertex, a face-shape pair's object a shape, objects
/// that may collide, pairs sorted
/// without repeats; TOIs must lie in [0, 1]. @throws InputError (file, where, reason) otherwise.
CachedTruth read_truth_file(const std::filesystem::path& path, const Scene& scene);

class TruthCache {
 public:
  /// `warnings` receives one line per cached file that was bad and recomputed (nullptr: std::cerr).
  explicit TruthCache(std::filesystem::path directory, std::ostream* warnings = nullptr) : directory_(std::move(directory)), warnings_(warnings) {}

  /// The truth of the step, from the cache or computed by the reference (and then stored). `computed` tells which.
  /// With `with_toi`, every contact carries its exact TOI's floor (a cached file without TOIs is computed again).
  CollisionSet truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, bool& computed, bool with_toi = false) const;

  /// Where the truth of this step is (or would be) kept.
  std::filesystem::path file_for(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1) const;

 private:
  std::filesystem::path directory_;
  std::ostream* warnings_;
};

}  // namespace ccd::harness
