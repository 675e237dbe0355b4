#include "strategies/opencl/self_test.hpp"

#include "strategies/narrowphase/round_to_nearest.hpp"
#include "strategies/narrowphase/shared.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>
#include <vector>

namespace ccd::opencl {
namespace {

/// Settings of the pairs' narrow phases: the defaults of conservative and cubic64.
constexpr double kTolerance = 1e-6;
constexpr double kToiTolerance = 1e-6;
constexpr long kMaxIterations = 20000;
constexpr double kEta = 1e-6;
constexpr std::size_t kPairs = 512;
/// The pairs' scales: pair i's coordinates are of size 2^(100 (i mod kScales) - 900).
constexpr std::size_t kScales = 19;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
/// The device's output is the host's: the same bits, or both NaN (a TOI of a pair that does not collide).
bool same_output(double device, double host) { return (std::isnan(device) && std::isnan(host)) || same_bits(device, host); }

std::string hex(double value) {
  std::ostringstream out;
  out << std::hexfloat << value;
  return out.str();
}

[[noreturn]] void refuse(const Context& context, const std::string& what) {
  throw std::invalid_argument("OpenCL device " + std::to_string(context.device().index) + " (" + context.device().name +
                              ") does not compute what the host computes: " + what +
                              "; its answers could not match the CPU backend's, so it is not used");
}

/// The self-test's pairs (seeded): points, edges and faces at scales from 2^-900 to 2^900, moving by their size or
/// much less, half of them with two points made to (nearly) meet.
struct SelfTestPairs {
  std::vector<double> rows = std::vector<double>(kPairs * 24), thickness = std::vector<double>(kPairs);
  std::vector<int> kinds = std::vector<int>(kPairs);
};
SelfTestPairs self_test_pairs() {
  SelfTestPairs p;
  std::vector<double>& rows = p.rows;
  std::vector<double>& thickness = p.thickness;
  std::vector<int>& kinds = p.kinds;
  std::mt19937_64 random(kSelfTestSeed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (std::size_t i = 0; i < kPairs; ++i) {
    const int exponent = static_cast<int>(i % kScales) * 100 - 900;
    const double motion = i % 3 == 0 ? 1.0 : (i % 3 == 1 ? 0.1 : 1e-3);
    for (int k = 0; k < 12; ++k) rows[24 * i + static_cast<std::size_t>(k)] = std::ldexp(unit(random), exponent);
    for (int k = 12; k < 24; ++k) {
      rows[24 * i + static_cast<std::size_t>(k)] = rows[24 * i + static_cast<std::size_t>(k - 12)] + std::ldexp(motion * unit(random), exponent);
    }
    if (i % 2 == 0) {  // the second point onto the first: a contact or a near miss
      for (int k = 0; k < 3; ++k) rows[24 * i + 3 + static_cast<std::size_t>(k)] = rows[24 * i + static_cast<std::size_t>(k)] * (1 + 1e-9);
    }
    thickness[i] = i % 4 == 0 ? 0.0 : std::ldexp(0.05 * (1 + unit(random)), exponent);
    kinds[i] = static_cast<int>(i % 2);
  }
  return p;
}

/// Pair i's eight rows.
std::array<narrowphase::shared::f64::ccd_v3, 8> rows_of(const SelfTestPairs& p, std::size_t i) {
  std::array<narrowphase::shared::f64::ccd_v3, 8> r;
  for (std::size_t k = 0; k < 8; ++k) {
    const std::size_t at = 24 * i + 3 * k;
    r[k] = narrowphase::shared::f64::ccd_v3_make(p.rows[at], p.rows[at + 1], p.rows[at + 2]);
  }
  return r;
}

/// The conservative test of pair i of `p` at `thickness` on the host, with all the room it needs.
narrowphase::shared::f64::ccd_conservative_outcome host_conservative(const SelfTestPairs& p, std::size_t i, double thickness,
                                                                     std::vector<narrowphase::shared::f64::ccd_sub_box>& storage) {
  return narrowphase::shared::f64::ccd_conservative_test(rows_of(p, i).data(), thickness, p.kinds[i], kTolerance, kToiTolerance, kMaxIterations, 0,
                                                         storage.data(), static_cast<int>(storage.size()));
}

}  // namespace

void check_device_arithmetic(Context& context) {
  // a·b + c with a = 1 + 2^-30, b = 1 - 2^-30, c = -1: the product 1 - 2^-60 rounds to 1, so the sum is 0; an FMA
  // keeps -2^-60. DBL_MIN / 2 is subnormal (0 when flushed); 3·2^-1074 - 2^-1074 = 2^-1073.
  const std::vector<double> in{1 + 0x1p-30, 1 - 0x1p-30, -1.0, 0x1p-1022, 0x1p-1074, 2.0, 3.0};
  const double expected[5] = {0.0, 0x1p-1023, 0x1p-1073, std::sqrt(2.0), 1.0 / 3.0};
  const char* meaning[5] = {"a*b+c was contracted into a fused multiply-add", "a subnormal double was flushed to zero",
                            "subnormal arithmetic is not exact", "sqrt is not correctly rounded", "division is not correctly rounded"};
  Buffer input, output;
  upload(context, input, in.data(), in.size());
  output.reserve(context, 5 * sizeof(double));
  cl_kernel arithmetic = context.kernel("self_test_arithmetic");
  set_arguments(arithmetic, input.get(), output.get());
  launch(context, arithmetic, 1, 1, nullptr);
  std::vector<double> got(5);
  download(context, output, got.data(), got.size());
  for (int i = 0; i < 5; ++i) {
    if (!same_bits(got[static_cast<std::size_t>(i)], expected[i])) {
      refuse(context, std::string(meaning[i]) + " (got " + hex(got[static_cast<std::size_t>(i)]) + ", the host " + hex(expected[i]) + ")");
    }
  }

  // Seeded pairs: random positions and motions at scales 2^-900..2^900, half of them nearly touching.
  const SelfTestPairs p = self_test_pairs();
  const std::vector<double>& rows = p.rows;
  const std::vector<double>& thickness = p.thickness;
  const std::vector<int>& kinds = p.kinds;
  Buffer rows_buffer, kinds_buffer, thickness_buffer, out_buffer;
  upload(context, rows_buffer, rows.data(), rows.size());
  upload(context, kinds_buffer, kinds.data(), kinds.size());
  upload(context, thickness_buffer, thickness.data(), thickness.size());
  out_buffer.reserve(context, kPairs * 6 * sizeof(double));
  cl_kernel pairs = context.kernel("self_test_pairs");
  const cl_uint count = static_cast<cl_uint>(kPairs);
  const cl_double tolerance = kTolerance, toi_tolerance = kToiTolerance, eta = kEta;
  const cl_long max_iterations = kMaxIterations;
  set_arguments(pairs, count, rows_buffer.get(), kinds_buffer.get(), thickness_buffer.get(), tolerance, toi_tolerance, max_iterations, eta,
                out_buffer.get());
  launch(context, pairs, kPairs, 64, nullptr);
  std::vector<double> device(kPairs * 6);
  download(context, out_buffer, device.data(), device.size());

  const narrowphase::RoundToNearest rounding;
  std::vector<narrowphase::shared::f64::ccd_sub_box> storage(1 << 16);
  for (std::size_t i = 0; i < kPairs; ++i) {
    const auto c = host_conservative(p, i, thickness[i], storage);
    const auto q = narrowphase::shared::f64::ccd_cubic_test(rows_of(p, i).data(), thickness[i], kEta, kinds[i]);
    const double host[6] = {static_cast<double>(c.collides), c.toi, c.achieved_tolerance, static_cast<double>(q.collides), q.toi, q.reach};
    const char* field[6] = {"conservative's answer", "conservative's TOI", "conservative's tolerance",
                            "cubic64's answer",      "cubic64's TOI",      "cubic64's reach"};
    for (int k = 0; k < 6; ++k) {
      const double d = device[6 * i + static_cast<std::size_t>(k)];
      if (k < 3 && device[6 * i] < 0) continue;  // the device ran out of sub-boxes: the host decides such pairs
      if (!same_output(d, host[k])) {
        refuse(context, std::string(field[k]) + " differs on self-test pair " + std::to_string(i) + " of seed " + std::to_string(kSelfTestSeed) +
                            " (device " + hex(d) + ", host " + hex(host[k]) + ")");
      }
    }
  }
}

// The device's sub-box is the host's: the deep pass's store is sized by it.
static_assert(sizeof(narrowphase::shared::f64::ccd_sub_box) == kSubBoxBytes);

void check_deep_pass_arithmetic(Context& context, std::size_t capacity) {
  // Each pair as the deep pass meets it: its four points as vertices 4i..4i+3 of x0 and x1, a vertex-face pair's
  // face as face i, through the deep pass's own kernel, whose thickness is one for a launch: every pair at δ = 0,
  // then each scale's pairs (kScales) at the δ of one of them. (One launch a pair, each at its own δ, ran the 512
  // searches one after another.)
  const SelfTestPairs p = self_test_pairs();
  std::vector<double> x0(kPairs * 12), x1(kPairs * 12);
  std::vector<cl_uint> faces(kPairs * 3);
  std::vector<cl_uint4> pairs(kPairs);
  for (std::size_t i = 0; i < kPairs; ++i) {
    std::copy_n(p.rows.begin() + static_cast<std::ptrdiff_t>(24 * i), 12, x0.begin() + static_cast<std::ptrdiff_t>(12 * i));
    std::copy_n(p.rows.begin() + static_cast<std::ptrdiff_t>(24 * i + 12), 12, x1.begin() + static_cast<std::ptrdiff_t>(12 * i));
    const auto v = static_cast<cl_uint>(4 * i);
    for (cl_uint k = 0; k < 3; ++k) faces[3 * i + k] = v + 1 + k;
    pairs[i] = p.kinds[i] != 0 ? cl_uint4{{v, static_cast<cl_uint>(i), kVertexFacePair, 0}} : cl_uint4{{v, v + 1, v + 2, v + 3}};
  }
  Buffer x0_buffer, x1_buffer, faces_buffer, pairs_buffer, sub_boxes, status, toi;
  upload(context, x0_buffer, x0.data(), x0.size());
  upload(context, x1_buffer, x1.data(), x1.size());
  upload(context, faces_buffer, faces.data(), faces.size());
  sub_boxes.reserve(context, kPairs * capacity * kSubBoxBytes);
  status.reserve(context, kPairs);
  toi.reserve(context, kPairs * sizeof(double));
  cl_kernel kernel = context.kernel("narrow_conservative_deep", Context::Build::deep);
  const cl_double tolerance = kTolerance, toi_tolerance = kToiTolerance;
  const cl_long max_iterations = kMaxIterations;
  const narrowphase::RoundToNearest rounding;
  std::vector<narrowphase::shared::f64::ccd_sub_box> storage(1 << 16);
  for (std::size_t group = 0; group <= kScales; ++group) {
    // group kScales: every pair at δ = 0; else the pairs of scale `group` at the δ of its first pair that has one.
    std::vector<std::size_t> members;
    double thickness = 0;
    for (std::size_t i = 0; i < kPairs; ++i) {
      if (group < kScales && i % kScales != group) continue;
      if (group < kScales && thickness == 0) thickness = p.thickness[i];
      members.push_back(i);
    }
    std::vector<cl_uint4> launched(members.size());
    for (std::size_t j = 0; j < members.size(); ++j) launched[j] = pairs[members[j]];
    upload(context, pairs_buffer, launched.data(), launched.size());
    set_arguments(kernel, static_cast<cl_uint>(launched.size()), pairs_buffer.get(), faces_buffer.get(), x0_buffer.get(), x1_buffer.get(), thickness,
                  tolerance, toi_tolerance, max_iterations, sub_boxes.get(), static_cast<cl_uint>(capacity), status.get(), toi.get());
    launch(context, kernel, launched.size(), 64, nullptr);
    std::vector<cl_uchar> device_status(launched.size());
    std::vector<double> device_toi(launched.size());
    download(context, status, device_status.data(), launched.size());
    download(context, toi, device_toi.data(), launched.size());
    for (std::size_t j = 0; j < members.size(); ++j) {
      if (device_status[j] == 3) continue;  // out of these sub-boxes too: the host decides such pairs
      const std::size_t i = members[j];
      const auto c = host_conservative(p, i, thickness, storage);
      const double device[2] = {static_cast<double>(device_status[j]), device_toi[j]};
      const double host[2] = {static_cast<double>(c.collides), c.toi};
      const char* field[2] = {"the deep pass's answer", "the deep pass's TOI"};
      for (std::size_t k = 0; k < 2; ++k) {
        if (!same_output(device[k], host[k])) {
          refuse(context, std::string(field[k]) + " differs on self-test pair " + std::to_string(i) + " of seed " + std::to_string(kSelfTestSeed) +
                              " at δ " + hex(thickness) + " (device " + hex(device[k]) + ", host " + hex(host[k]) + ")");
        }
      }
    }
  }
}

}  // namespace ccd::opencl
