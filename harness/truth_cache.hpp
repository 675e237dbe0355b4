#pragma once
/// @file
/// Whole-step truth, computed once per step and kept on disk: keyed by the step's content (positions and
/// topology), δ, the collision filter (self flags, collidable pairs) and the reference's version.

#include "core/collision_set.hpp"
#include "core/scene.hpp"

#include <filesystem>
#include <span>
#include <string>

namespace ccd::harness {

/// Bump when the reference could decide anything differently: old cached truth is then never read.
inline constexpr const char* kReferenceVersion = "reference-1";

/// A 128-bit content key, as 32 hex digits.
std::string truth_key(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1);

class TruthCache {
 public:
  explicit TruthCache(std::filesystem::path directory) : directory_(std::move(directory)) {}

  /// The truth of the step, from the cache or computed by the reference (and then stored). `computed` tells which.
  CollisionSet truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, bool& computed) const;

 private:
  std::filesystem::path directory_;
};

}  // namespace ccd::harness
