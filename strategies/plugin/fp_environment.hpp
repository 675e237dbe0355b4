#pragma once
/// @file
/// The floating-point environment of the calling thread, as far as it changes what arithmetic computes: the rounding
/// mode and, on x86-64, the SSE control register's flush-to-zero and denormals-are-zero bits (MXCSR) and the x87
/// control word. A plugin can change it (a library built with GCC's fast-math options turns FTZ and DAZ on when it is
/// loaded: GCC links crtfastmath.o into it), and the exact reference and the conservative tests assume IEEE
/// arithmetic in round-to-nearest (docs/DESIGN.md §8): so ccdbench reads it before and after every in-process call
/// into a plugin and puts its own back (call_guard.hpp).

#include <cstdint>
#include <string>

namespace ccd::plugin {

struct FpEnvironment {
  /// The x87 control word (precision and rounding) and MXCSR's control bits (exception masks, rounding, FTZ, DAZ);
  /// the sticky exception flags are left out: they say what happened, not how arithmetic behaves.
  std::uint16_t x87_control = 0;
  std::uint32_t mxcsr_control = 0;

  /// The calling thread's environment.
  static FpEnvironment current();
  /// Makes it the calling thread's environment.
  void install() const;
  bool operator==(const FpEnvironment& other) const { return x87_control == other.x87_control && mxcsr_control == other.mxcsr_control; }
  bool operator!=(const FpEnvironment& other) const { return !(*this == other); }
  /// "MXCSR 0x1f80, rounding to nearest": the register and what it means.
  std::string describe() const;
};

/// What changed from `before` to `after`, in words: "flush-to-zero on, denormals-are-zero on (MXCSR 0x1f80 ->
/// 0x9fc0)", "rounding to nearest -> upward (...)". Empty when they are equal.
std::string describe_change(const FpEnvironment& before, const FpEnvironment& after);

}  // namespace ccd::plugin
