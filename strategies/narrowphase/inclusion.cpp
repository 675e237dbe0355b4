#include "strategies/narrowphase/inclusion.hpp"

#include "strategies/narrowphase/exact_scaling.hpp"
#include "strategies/narrowphase/shared.hpp"

#include <sstream>
#include <vector>

namespace ccd::narrowphase {
namespace {

/// The search, compiled twice: for the x86-64 baseline and for x86-64-v3 (AVX2), chosen when the program loads
/// (GCC function multiversioning), so one binary runs on any x86-64 and uses wide vectors where they exist. The
/// arithmetic is the same IEEE operations in the same order either way (-ffp-contract=off holds for both clones,
/// so FMA never fuses a product into a sum): the same answers bit for bit (tests/strategies/full_answers_test.cpp).
/// `flatten` inlines the whole search into each clone; otherwise both would call the one baseline copy.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default"), flatten))
#endif
shared::f64::ccd_conservative_outcome conservative_search(const shared::f64::ccd_v3 rows[8], double thickness, bool vertex_face,
                                                          double tolerance, long max_iterations, shared::f64::ccd_sub_box* storage,
                                                          int capacity) {
  return shared::f64::ccd_conservative_test(rows, thickness, vertex_face, tolerance, max_iterations, 0, storage, capacity);
}

/// The search itself, its error budget and its stages are shared/inclusion.h's (the text the OpenCL kernels
/// compile too); this class gives it round-to-nearest and as much sub-box storage as a query needs.
class InclusionTest final : public NarrowPhase {
 public:
  explicit InclusionTest(const InclusionSettings& settings) : settings_(settings) {}

  std::string name() const override {
    std::ostringstream out;
    out << "conservative:tolerance=" << settings_.tolerance << ":max_iterations=" << settings_.max_iterations;
    return out.str();
  }
  bool conservative() const override { return true; }
  NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const override { return test(rows, thickness, true); }
  NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const override { return test(rows, thickness, false); }

 private:
  NarrowPhaseResult test(const PairRows& original, double thickness, bool vertex_face) const {
    const RoundToNearest rounding;
    const auto rows = shared::to_shared_rows(original);
    // Nearly every query fits in kInlineBoxes; the search is deterministic, so a query that overflows is run
    // again from the start with more room and gives the answer it would have given.
    shared::f64::ccd_sub_box inline_boxes[kInlineBoxes];
    std::vector<shared::f64::ccd_sub_box> more;
    shared::f64::ccd_sub_box* storage = inline_boxes;
    int capacity = kInlineBoxes;
    while (true) {
      const shared::f64::ccd_conservative_outcome outcome =
          conservative_search(rows.data(), thickness, vertex_face, settings_.tolerance, settings_.max_iterations, storage, capacity);
      if (!outcome.overflow) return {outcome.collides != 0, outcome.toi, outcome.hit_iteration_cap != 0, outcome.achieved_tolerance};
      capacity *= 4;
      more.resize(static_cast<std::size_t>(capacity));
      storage = more.data();
    }
  }

  static constexpr int kInlineBoxes = 128;
  InclusionSettings settings_;
};

}  // namespace

std::unique_ptr<NarrowPhase> make_inclusion(const InclusionSettings& settings) {
  return std::make_unique<InclusionTest>(settings);
}

}  // namespace ccd::narrowphase
