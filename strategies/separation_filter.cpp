#include "strategies/separation_filter.hpp"

#include "strategies/narrowphase/round_to_nearest.hpp"
#include "strategies/narrowphase/shared.hpp"

namespace ccd::strategies {

// The filter itself is narrowphase/shared/separation.h, the text the OpenCL kernels compile too (apccd's backends
// must drop the same elementary pairs); its error budget is written there.
// The whole filter inlined into this one function (GCC's flatten): faster where it runs millions of times a step
// (reports/cpu-step measures it; a multiversioned copy for x86-64-v3 gained nothing more). Inlining moves no
// operation: the same answers (FullAnswers, OpenCL parity).
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((flatten))
#endif
bool provably_apart(const narrowphase::PairRows& original, bool vertex_face, double thickness) {
  const narrowphase::RoundToNearest rounding;
  std::array<narrowphase::shared::f64::ccd_v3, 8> rows = narrowphase::shared::to_shared_rows(original);
  return narrowphase::shared::f64::ccd_provably_apart(rows.data(), vertex_face ? 1 : 0, thickness) != 0;
}

}  // namespace ccd::strategies
