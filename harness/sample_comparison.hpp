#pragma once
/// @file
/// Checks whole-step truth against a Scalable-CCD sample step's own truth (its candidates and mma_bool labels).

#include "core/collision_set.hpp"
#include "datasets/sample_step.hpp"

#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

namespace ccd::harness {

struct SampleComparison {
  /// Pairs the sample labels colliding, and how many of them our truth has (VF by vertex and face id,
  /// EE by matching the query coordinates to mesh vertices).
  std::size_t vertex_face_positives = 0;
  std::size_t vertex_face_found = 0;
  std::size_t edge_edge_positives = 0;
  std::size_t edge_edge_found = 0;
  /// Colliding pairs of our truth that the sample's candidate list does not hold at all.
  std::size_t vertex_face_outside_candidates = 0;
  std::size_t edge_edge_outside_candidates = 0;
  /// Up to 20 sample positives our truth lacks, described by ids.
  std::vector<std::string> missing;
};

SampleComparison compare_with_sample(const datasets::SampleStep& step, const CollisionSet& truth);

nlohmann::json to_json(const SampleComparison& comparison);

}  // namespace ccd::harness
