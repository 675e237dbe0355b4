#pragma once
/// @file
/// What the conservative tests (the `conservative` narrow phase, the separation filter, the face-shape decisions)
/// do before anything else: run in round-to-nearest, which their error budgets assume. They then rescale the pair
/// exactly by a power of two (shared/scaling.h), so that those budgets hold at every scale (docs/DESIGN.md §6).

namespace ccd::narrowphase {

/// Round-to-nearest for its lifetime, restoring the caller's mode after: the error budgets of the conservative
/// tests assume it, and the reference switches rounding modes in the same process for its interval arithmetic.
class RoundToNearest {
 public:
  RoundToNearest();
  ~RoundToNearest();
  RoundToNearest(const RoundToNearest&) = delete;
  RoundToNearest& operator=(const RoundToNearest&) = delete;

 private:
  int saved_;
};

}  // namespace ccd::narrowphase
