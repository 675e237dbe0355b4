#include "reference/elementary_pair.hpp"

#include "reference/certified_filter.hpp"
#include "reference/exact_decision.hpp"
#include "reference/unit_scale.hpp"

#include <cmath>
#include <stdexcept>

namespace ccd::reference {

namespace {

/// The filter first when asked, then the exact path; `exact_inputs()` builds the rationals only when needed. Both
/// decide the pair brought to unit size (unit_scale.hpp): the same question as the pair given.
template <class ExactInputs>
Decision filter_then_exact(PairKind kind, const ScaledIntervals& intervals, const DecisionRequest& request, ExactInputs exact_inputs) {
  if (request.use_filter) {
    const FilterVerdict verdict = filter_decide(kind, intervals.rows, intervals.thickness);
    if (verdict == FilterVerdict::certainly_no) return {false, DecidedBy::filter, std::nullopt, std::nullopt, std::nullopt};
    if (verdict == FilterVerdict::certainly_yes && !request.want_toi) return {true, DecidedBy::filter, std::nullopt, std::nullopt, std::nullopt};
  }
  const auto [pair, exact_thickness] = exact_inputs();
  const ExactResult exact = decide_exactly(pair, exact_thickness, request.want_toi ? request.toi_bits : 0);
  return {exact.collides, DecidedBy::exact, exact.toi, exact.toi_floor, exact.toi_ceiling};
}

}  // namespace

Decision decide(const ExactPair& pair, const mpq_class& thickness, const DecisionRequest& request) {
  const int exponent = unit_scale_exponent(pair, thickness);
  return filter_then_exact(pair.kind, scaled_intervals(pair, thickness, exponent), request,
                           [&] { return scaled_exactly(pair, thickness, exponent); });
}

Decision decide(PairKind kind, const std::array<Vec3, 8>& rows, double thickness, const DecisionRequest& request) {
  if (!std::isfinite(thickness) || thickness < 0) throw std::invalid_argument("reference: δ must be finite and >= 0");
  const int exponent = unit_scale_exponent(rows, thickness);
  return filter_then_exact(kind, scaled_intervals(rows, thickness, exponent), request,
                           [&] { return scaled_exactly(exact_pair_from_doubles(kind, rows), mpq_class(thickness), exponent); });
}

}  // namespace ccd::reference
