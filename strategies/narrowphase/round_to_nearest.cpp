#include "strategies/narrowphase/round_to_nearest.hpp"

#include <cfenv>

namespace ccd::narrowphase {

RoundToNearest::RoundToNearest() : saved_(std::fegetround()) {
  if (saved_ != FE_TONEAREST) std::fesetround(FE_TONEAREST);
}

RoundToNearest::~RoundToNearest() {
  if (saved_ != FE_TONEAREST) std::fesetround(saved_);
}

}  // namespace ccd::narrowphase
