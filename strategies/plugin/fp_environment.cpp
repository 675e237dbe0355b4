#include "strategies/plugin/fp_environment.hpp"

#include <cfenv>
#include <cstdio>

#if defined(__x86_64__)
#include <xmmintrin.h>
#endif

namespace ccd::plugin {
namespace {

#if defined(__x86_64__)
// MXCSR (Intel SDM vol. 1, 10.2.3): bits 0-5 are the sticky exception flags, 6 DAZ, 7-12 the exception masks,
// 13-14 the rounding control, 15 FTZ.
constexpr std::uint32_t kMxcsrFlags = 0x3f;
constexpr std::uint32_t kMxcsrDaz = 1u << 6;
constexpr std::uint32_t kMxcsrFtz = 1u << 15;
constexpr std::uint32_t kMxcsrRounding = 3u << 13;
constexpr std::uint32_t kMxcsrMasks = 0x3fu << 7;
#endif

const char* rounding_name(int mode) {
  switch (mode) {
    case FE_TONEAREST: return "to nearest";
    case FE_UPWARD: return "upward";
    case FE_DOWNWARD: return "downward";
    case FE_TOWARDZERO: return "toward zero";
    default: return "unknown";
  }
}

#if defined(__x86_64__)
int rounding_of_mxcsr(std::uint32_t mxcsr) {
  switch ((mxcsr & kMxcsrRounding) >> 13) {
    case 0: return FE_TONEAREST;
    case 1: return FE_DOWNWARD;
    case 2: return FE_UPWARD;
    default: return FE_TOWARDZERO;
  }
}
#endif

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%x", value);
  return text;
}

}  // namespace

FpEnvironment FpEnvironment::current() {
  FpEnvironment environment;
#if defined(__x86_64__)
  std::uint16_t control = 0;
  asm volatile("fnstcw %0" : "=m"(control));
  environment.x87_control = control;
  environment.mxcsr_control = _mm_getcsr() & ~kMxcsrFlags;
#else
  environment.mxcsr_control = static_cast<std::uint32_t>(std::fegetround());
#endif
  return environment;
}

void FpEnvironment::install() const {
#if defined(__x86_64__)
  std::uint16_t control = x87_control;
  asm volatile("fldcw %0" : : "m"(control));
  _mm_setcsr((_mm_getcsr() & kMxcsrFlags) | mxcsr_control);
#else
  std::fesetround(static_cast<int>(mxcsr_control));
#endif
}

std::string FpEnvironment::describe() const {
#if defined(__x86_64__)
  std::string text = "MXCSR " + hex(mxcsr_control) + ", rounding " + rounding_name(rounding_of_mxcsr(mxcsr_control));
  if (mxcsr_control & kMxcsrFtz) text += ", flush-to-zero";
  if (mxcsr_control & kMxcsrDaz) text += ", denormals-are-zero";
  return text + ", x87 control " + hex(x87_control);
#else
  return std::string("rounding ") + rounding_name(static_cast<int>(mxcsr_control));
#endif
}

std::string describe_change(const FpEnvironment& before, const FpEnvironment& after) {
  if (before == after) return {};
  std::string what;
  auto add = [&](const std::string& part) { what += (what.empty() ? "" : ", ") + part; };
#if defined(__x86_64__)
  const std::uint32_t changed = before.mxcsr_control ^ after.mxcsr_control;
  if (changed & kMxcsrRounding) {
    add(std::string("rounding ") + rounding_name(rounding_of_mxcsr(before.mxcsr_control)) + " -> " +
        rounding_name(rounding_of_mxcsr(after.mxcsr_control)));
  }
  if (changed & kMxcsrFtz) add(std::string("flush-to-zero ") + (after.mxcsr_control & kMxcsrFtz ? "on" : "off"));
  if (changed & kMxcsrDaz) add(std::string("denormals-are-zero ") + (after.mxcsr_control & kMxcsrDaz ? "on" : "off"));
  if (changed & kMxcsrMasks) add("exception masks changed");
  if (before.x87_control != after.x87_control) add("x87 control word " + hex(before.x87_control) + " -> " + hex(after.x87_control));
  return what + " (MXCSR " + hex(before.mxcsr_control) + " -> " + hex(after.mxcsr_control) + ")";
#else
  return std::string("rounding ") + rounding_name(static_cast<int>(before.mxcsr_control)) + " -> " +
         rounding_name(static_cast<int>(after.mxcsr_control));
#endif
}

}  // namespace ccd::plugin
