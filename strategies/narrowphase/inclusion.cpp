/// @file
/// `conservative`: certified in every stage (shared/inclusion.h): time windows from the coplanarity cubic with a
/// forward error bound, a cheap proof of a contact, and an inclusion search over (t, u, v) within the windows. It
/// never misses: every answer "no" is proven; "yes" may be a false alarm within the distance tolerance, or because
/// the iteration cap was hit (reported). Its TOI is never later than the exact earliest contact, and no earlier than
/// a proven contact by more than toi_tolerance.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/round_to_nearest.hpp"
#include "strategies/narrowphase/shared.hpp"

#include <vector>

namespace ccd::narrowphase {
namespace {

struct InclusionSettings {
  /// Distance tolerance as a fraction of the pair's bounding-box diagonal: a sub-box whose every point lies
  /// within δ + tolerance is reported as a contact.
  double tolerance = 1e-10;
  /// The TOI's tolerance in time, a fraction of the step: a reported TOI is never later than the earliest contact,
  /// and for a contact the search proves or holds in an accepted box, no earlier than it by more than this.
  double toi_tolerance = 1e-6;
  /// Sub-boxes examined before giving up (and answering "collides").
  long max_iterations = 20000;
};

/// The search, compiled twice: for the x86-64 baseline and for x86-64-v3 (AVX2), chosen when the program loads
/// (GCC function multiversioning), so one binary runs on any x86-64 and uses wide vectors where they exist. The
/// arithmetic is the same IEEE operations in the same order either way (-ffp-contract=off holds for both clones,
/// so FMA never fuses a product into a sum): the same answers bit for bit (tests/strategies/full_answers_test.cpp).
/// `flatten` inlines the whole search into each clone; otherwise both would call the one baseline copy.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default"), flatten))
#endif
shared::f64::ccd_conservative_outcome
conservative_search(const shared::f64::ccd_v3 rows[8], double thickness, bool vertex_face, double tolerance, double toi_tolerance,
                    long max_iterations, shared::f64::ccd_sub_box* storage, int capacity) {
  return shared::f64::ccd_conservative_test(rows, thickness, vertex_face, tolerance, toi_tolerance, max_iterations, 0, storage, capacity);
}

/// The search itself, its error budget and its stages are shared/inclusion.h's (the text the OpenCL kernels
/// compile too); this class gives it round-to-nearest and as much sub-box storage as a query needs.
class InclusionTest final : public NarrowPhase {
 public:
  explicit InclusionTest(const InclusionSettings& settings) : settings_(settings) {}

  std::string name() const override {
    return "conservative:tolerance=" + format_spec_number(settings_.tolerance) + ":toi_tolerance=" + format_spec_number(settings_.toi_tolerance) +
           ":max_iterations=" + std::to_string(settings_.max_iterations);
  }
  bool conservative() const override { return true; }
  std::optional<DeviceForm> device_form() const override {
    return DeviceForm{DeviceForm::Kernel::conservative, settings_.tolerance, settings_.toi_tolerance, settings_.max_iterations};
  }
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
      const shared::f64::ccd_conservative_outcome outcome = conservative_search(rows.data(), thickness, vertex_face, settings_.tolerance,
                                                                                settings_.toi_tolerance, settings_.max_iterations, storage, capacity);
      if (!outcome.overflow) return {outcome.collides != 0, outcome.toi, outcome.hit_iteration_cap != 0, outcome.achieved_tolerance, {}};
      capacity *= 4;
      more.resize(static_cast<std::size_t>(capacity));
      storage = more.data();
    }
  }

  static constexpr int kInlineBoxes = 128;
  InclusionSettings settings_;
};

}  // namespace

std::vector<NarrowPhaseEntry> inclusion_entries() {
  const InclusionSettings defaults;
  return {{"conservative",
           "certified time windows, a contact proof and an inclusion search over (t, u, v): never misses at any scale; "
           "its TOI is never late and tight to toi_tolerance",
           {KeySpec::number("tolerance", defaults.tolerance, kFractionOfPairRange,
                            "distance tolerance of an accepted sub-box, a fraction of the pair's box diagonal"),
            KeySpec::number("toi_tolerance", defaults.toi_tolerance, kFractionOfStepRange,
                            "TOI tolerance in time, a fraction of the step: never later than the contact, and no earlier "
                            "than a proven one by more than this"),
            KeySpec::integer("max_iterations", defaults.max_iterations, kIterationRange,
                             "sub-boxes examined before giving up (and answering \"collides\")")},
           true,
           {{"tolerance", {"1e-2", "1e-4", "1e-6", "1e-8", "1e-10", "1e-12"}}, {"toi_tolerance", {"1e-2", "1e-4", "1e-8", "1e-10"}}},
           [](const SpecReader& keys) -> std::unique_ptr<NarrowPhase> {
             return std::make_unique<InclusionTest>(
                 InclusionSettings{keys.number("tolerance"), keys.number("toi_tolerance"), keys.integer("max_iterations")});
           }}};
}

}  // namespace ccd::narrowphase
