/* A plugin from a C++ class with the two calls of ipc-toolkit's NarrowPhaseCCD, in one macro (header-only; needs
 * only ccdbench_plugin.h and the standard library):
 *
 *   struct MyCCD {
 *     bool point_triangle_ccd(const V& p_t0, const V& t0_t0, const V& t1_t0, const V& t2_t0,
 *                             const V& p_t1, const V& t0_t1, const V& t1_t1, const V& t2_t1,
 *                             double& toi, double min_distance, double tmax) const;
 *     bool edge_edge_ccd(const V& ea0_t0, const V& ea1_t0, const V& eb0_t0, const V& eb1_t0,
 *                        const V& ea0_t1, const V& ea1_t1, const V& eb0_t1, const V& eb1_t1,
 *                        double& toi, double min_distance, double tmax) const;
 *   };
 *   CCDBENCH_PLUGIN_FROM_CCD_CLASS(MyCCD, ccdbench::Vector3, "my-ccd", "1.0", "one line", CCDBENCH_REPORTS_TOI)
 *
 * V is any type constructible from three doubles (ccdbench::Vector3, Eigen::Vector3d, ...). ccdbench passes the
 * thickness as min_distance and 1 as tmax; a call that returns true reports a contact at `toi`; one that throws
 * reports an error with the exception's message (never a contact). The class is default-constructed once per
 * context.
 *
 * The plugin answers queries (`queries --method plugin:PATH`, `run --strategy full+plugin:PATH`) and whole steps
 * (`run --strategy plugin:PATH`): each step, the triangles' swept boxes (grown by the thickness) are sorted along x
 * and swept, starting from the order of the step before (an insertion sort: a state kept across steps, which costs
 * little when the mesh moves little), and every vertex-face and edge-edge pair of two overlapping triangles that the
 * scene lets collide is asked of the class once, unless the vertex's and the face's (or the two edges') swept boxes,
 * one grown by the thickness, do not meet.
 */
#ifndef CCDBENCH_PLUGIN_HPP
#define CCDBENCH_PLUGIN_HPP

#include "ccdbench_plugin.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <new>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace ccdbench {

/// A point, for classes that have no vector type of their own.
struct Vector3 {
  double x = 0, y = 0, z = 0;
  Vector3() = default;
  Vector3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

namespace detail {

template <class V>
V point(const double* rows, int k) {
  return V(rows[3 * k], rows[3 * k + 1], rows[3 * k + 2]);
}

/// One call of the class, as the ABI's answer.
template <class CCD, class V>
void ask(const CCD& ccd, const double* r, double thickness, bool vertex_face, ccdbench_answer* answer) {
  try {
    double toi = 1.0;
    const bool hit = vertex_face ? ccd.point_triangle_ccd(point<V>(r, 0), point<V>(r, 1), point<V>(r, 2), point<V>(r, 3), point<V>(r, 4),
                                                          point<V>(r, 5), point<V>(r, 6), point<V>(r, 7), toi, thickness, 1.0)
                                 : ccd.edge_edge_ccd(point<V>(r, 0), point<V>(r, 1), point<V>(r, 2), point<V>(r, 3), point<V>(r, 4), point<V>(r, 5),
                                                     point<V>(r, 6), point<V>(r, 7), toi, thickness, 1.0);
    answer->outcome = hit ? CCDBENCH_CONTACT : CCDBENCH_APART;
    answer->toi = toi;
  } catch (const std::exception& error) {
    answer->outcome = CCDBENCH_ERROR;
    std::snprintf(answer->message, CCDBENCH_MESSAGE_SIZE, "%s", error.what());
  } catch (...) {
    answer->outcome = CCDBENCH_ERROR;
    std::snprintf(answer->message, CCDBENCH_MESSAGE_SIZE, "an exception that is not a std::exception");
  }
}

/// The whole step made of the class's two calls, with the sort order kept from step to step.
template <class CCD, class V>
class WholeStep {
 public:
  explicit WholeStep(const ccdbench_scene& s)
      : vertex_count_(s.vertex_count),
        faces_(s.faces, s.faces + 3 * s.face_count),
        face_object_(s.face_object, s.face_object + s.face_count),
        self_(s.object_self_collision, s.object_self_collision + s.object_count) {
    for (std::size_t k = 0; k < s.collidable_count; ++k) {
      collidable_.insert(key(std::min(s.collidable[2 * k], s.collidable[2 * k + 1]), std::max(s.collidable[2 * k], s.collidable[2 * k + 1])));
    }
    order_.resize(s.face_count);
    for (std::uint32_t f = 0; f < s.face_count; ++f) order_[f] = f;
  }

  int step(const CCD& ccd, const ccdbench_step& st, const ccdbench_contacts& out, char* error) {
    const std::size_t faces = face_object_.size();
    // Each vertex's swept box, so that a pair whose boxes (one grown by the thickness) do not meet is never asked.
    vertex_boxes_.resize(vertex_count_);
    for (std::size_t v = 0; v < vertex_count_; ++v) {
      for (int c = 0; c < 3; ++c) {
        vertex_boxes_[v].low[c] = std::min(st.x0[3 * v + static_cast<std::size_t>(c)], st.x1[3 * v + static_cast<std::size_t>(c)]);
        vertex_boxes_[v].high[c] = std::max(st.x0[3 * v + static_cast<std::size_t>(c)], st.x1[3 * v + static_cast<std::size_t>(c)]);
      }
    }
    // Each triangle's swept box, grown by the thickness: the boxes that are sorted and swept.
    boxes_.resize(faces);
    for (std::size_t f = 0; f < faces; ++f) {
      const std::uint32_t* c = &faces_[3 * f];
      boxes_[f] = grown(joined(joined(vertex_boxes_[c[0]], vertex_boxes_[c[1]]), vertex_boxes_[c[2]]), st.thickness);
    }
    // The state across steps: the order of the step before, put right by an insertion sort.
    for (std::size_t i = 1; i < order_.size(); ++i) {
      const std::uint32_t f = order_[i];
      std::size_t j = i;
      while (j > 0 && boxes_[order_[j - 1]].low[0] > boxes_[f].low[0]) {
        order_[j] = order_[j - 1];
        --j;
      }
      order_[j] = f;
    }
    vertex_face_.clear();
    edge_edge_.clear();
    std::vector<double> rows(24);
    for (std::size_t i = 0; i < order_.size(); ++i) {
      const std::uint32_t a = order_[i];
      for (std::size_t j = i + 1; j < order_.size() && boxes_[order_[j]].low[0] <= boxes_[a].high[0]; ++j) {
        const std::uint32_t b = order_[j];
        if (!overlap(boxes_[a], boxes_[b]) || !may_collide(face_object_[a], face_object_[b])) continue;
        for (int k = 0; k < 3; ++k) {
          vertex_face(ccd, st, faces_[3 * a + static_cast<std::size_t>(k)], b, rows, out);
          vertex_face(ccd, st, faces_[3 * b + static_cast<std::size_t>(k)], a, rows, out);
          for (int m = 0; m < 3; ++m) edge_edge(ccd, st, edge(a, k), edge(b, m), rows, out);
        }
      }
    }
    // A pair the class could not answer makes the step fail (the ABI has no per-pair error in a step): its
    // message says which.
    if (!failure_.empty()) {
      std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", failure_.c_str());
      failure_.clear();
      return 1;
    }
    return 0;
  }

 private:
  struct Box {
    double low[3], high[3];
  };
  static std::uint64_t key(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }
  static bool overlap(const Box& a, const Box& b) {
    for (int c = 0; c < 3; ++c) {
      if (a.high[c] < b.low[c] || b.high[c] < a.low[c]) return false;
    }
    return true;
  }
  static Box joined(Box a, const Box& b) {
    for (int c = 0; c < 3; ++c) {
      a.low[c] = std::min(a.low[c], b.low[c]);
      a.high[c] = std::max(a.high[c], b.high[c]);
    }
    return a;
  }
  Box edge_box(std::pair<std::uint32_t, std::uint32_t> e) const { return joined(vertex_boxes_[e.first], vertex_boxes_[e.second]); }
  // Grown by the thickness, then one ulp out: the box still holds every point within the thickness of it.
  static Box grown(Box b, double thickness) {
    for (int c = 0; c < 3; ++c) {
      b.low[c] = std::nextafter(b.low[c] - thickness, -INFINITY);
      b.high[c] = std::nextafter(b.high[c] + thickness, INFINITY);
    }
    return b;
  }
  bool may_collide(std::uint32_t a, std::uint32_t b) const {
    return a == b ? self_[a] != 0 : collidable_.count(key(std::min(a, b), std::max(a, b))) > 0;
  }
  std::pair<std::uint32_t, std::uint32_t> edge(std::uint32_t f, int k) const {
    const std::uint32_t p = faces_[3 * f + static_cast<std::size_t>(k)], q = faces_[3 * f + static_cast<std::size_t>((k + 1) % 3)];
    return {std::min(p, q), std::max(p, q)};
  }
  static void copy(const ccdbench_step& st, std::uint32_t v, int slot, std::vector<double>& rows) {
    for (int c = 0; c < 3; ++c) {
      rows[static_cast<std::size_t>(3 * slot + c)] = st.x0[3 * v + static_cast<std::size_t>(c)];
      rows[static_cast<std::size_t>(3 * (slot + 4) + c)] = st.x1[3 * v + static_cast<std::size_t>(c)];
    }
  }
  void vertex_face(const CCD& ccd, const ccdbench_step& st, std::uint32_t v, std::uint32_t f, std::vector<double>& rows,
                   const ccdbench_contacts& out) {
    const std::uint32_t* c = &faces_[3 * f];
    if (v == c[0] || v == c[1] || v == c[2] || !overlap(vertex_boxes_[v], boxes_[f]) || !vertex_face_.insert(key(v, f)).second) return;
    copy(st, v, 0, rows);
    for (int k = 0; k < 3; ++k) copy(st, c[k], k + 1, rows);
    ccdbench_answer answer{};
    ask<CCD, V>(ccd, rows.data(), st.thickness, true, &answer);
    if (answer.outcome == CCDBENCH_CONTACT) out.vertex_face(out.host, v, f, answer.toi);
    if (answer.outcome == CCDBENCH_ERROR && failure_.empty())
      failure_ = "vertex " + std::to_string(v) + ", face " + std::to_string(f) + ": " + answer.message;
  }
  void edge_edge(const CCD& ccd, const ccdbench_step& st, std::pair<std::uint32_t, std::uint32_t> a, std::pair<std::uint32_t, std::uint32_t> b,
                 std::vector<double>& rows, const ccdbench_contacts& out) {
    if (a.first == b.first || a.first == b.second || a.second == b.first || a.second == b.second) return;
    if (!overlap(grown(edge_box(a), st.thickness), edge_box(b))) return;
    if (b < a) std::swap(a, b);
    if (!edge_edge_.insert({key(a.first, a.second), key(b.first, b.second)}).second) return;
    copy(st, a.first, 0, rows);
    copy(st, a.second, 1, rows);
    copy(st, b.first, 2, rows);
    copy(st, b.second, 3, rows);
    ccdbench_answer answer{};
    ask<CCD, V>(ccd, rows.data(), st.thickness, false, &answer);
    if (answer.outcome == CCDBENCH_CONTACT) out.edge_edge(out.host, a.first, a.second, b.first, b.second, answer.toi);
    if (answer.outcome == CCDBENCH_ERROR && failure_.empty()) {
      failure_ = "edges (" + std::to_string(a.first) + ", " + std::to_string(a.second) + ") and (" + std::to_string(b.first) + ", " +
                 std::to_string(b.second) + "): " + answer.message;
    }
  }

  std::size_t vertex_count_;
  std::vector<std::uint32_t> faces_, face_object_;
  std::vector<std::uint8_t> self_;
  std::unordered_set<std::uint64_t> collidable_;
  std::vector<std::uint32_t> order_;
  std::vector<Box> boxes_, vertex_boxes_;
  std::unordered_set<std::uint64_t> vertex_face_;
  std::set<std::pair<std::uint64_t, std::uint64_t>> edge_edge_;
  std::string failure_;
};

/// A context: the class, and the whole step's state once a scene is begun.
template <class CCD, class V>
struct Context {
  CCD ccd;
  WholeStep<CCD, V>* whole = nullptr;
  ~Context() { delete whole; }
};

}  // namespace detail
}  // namespace ccdbench

/* The plugin's table and entry point, from CLASS (see above). */
#define CCDBENCH_PLUGIN_FROM_CCD_CLASS(CLASS, VECTOR, NAME, VERSION, HELP, CAPABILITIES)                                 \
  namespace {                                                                                                            \
  using ccdbench_context_type = ::ccdbench::detail::Context<CLASS, VECTOR>;                                              \
  void* ccdbench_create(const char* const*, char* error) {                                                               \
    try {                                                                                                                \
      return new ccdbench_context_type();                                                                                \
    } catch (const std::exception& e) {                                                                                  \
      std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());                                                       \
      return nullptr;                                                                                                    \
    }                                                                                                                    \
  }                                                                                                                      \
  void ccdbench_destroy(void* c) { delete static_cast<ccdbench_context_type*>(c); }                                      \
  void ccdbench_vertex_face(void* c, const double* rows, double thickness, ccdbench_answer* answer) {                    \
    ::ccdbench::detail::ask<CLASS, VECTOR>(static_cast<ccdbench_context_type*>(c)->ccd, rows, thickness, true, answer);  \
  }                                                                                                                      \
  void ccdbench_edge_edge(void* c, const double* rows, double thickness, ccdbench_answer* answer) {                      \
    ::ccdbench::detail::ask<CLASS, VECTOR>(static_cast<ccdbench_context_type*>(c)->ccd, rows, thickness, false, answer); \
  }                                                                                                                      \
  int ccdbench_begin(void* c, const ccdbench_scene* scene, char* error) {                                                \
    auto* context = static_cast<ccdbench_context_type*>(c);                                                              \
    try {                                                                                                                \
      delete context->whole;                                                                                             \
      context->whole = new ::ccdbench::detail::WholeStep<CLASS, VECTOR>(*scene);                                         \
      return 0;                                                                                                          \
    } catch (const std::exception& e) {                                                                                  \
      std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());                                                       \
      return 1;                                                                                                          \
    }                                                                                                                    \
  }                                                                                                                      \
  int ccdbench_step(void* c, const ccdbench_step* step, const ccdbench_contacts* contacts, char* error) {                \
    auto* context = static_cast<ccdbench_context_type*>(c);                                                              \
    try {                                                                                                                \
      return context->whole->step(context->ccd, *step, *contacts, error);                                                \
    } catch (const std::exception& e) {                                                                                  \
      std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());                                                       \
      return 1;                                                                                                          \
    }                                                                                                                    \
  }                                                                                                                      \
  void ccdbench_end(void* c) {                                                                                           \
    auto* context = static_cast<ccdbench_context_type*>(c);                                                              \
    delete context->whole;                                                                                               \
    context->whole = nullptr;                                                                                            \
  }                                                                                                                      \
  const ccdbench_plugin ccdbench_table = {sizeof(ccdbench_plugin),                                                       \
                                          CCDBENCH_PLUGIN_ABI_VERSION,                                                   \
                                          NAME,                                                                          \
                                          VERSION,                                                                       \
                                          HELP,                                                                          \
                                          CAPABILITIES,                                                                  \
                                          nullptr,                                                                       \
                                          0,                                                                             \
                                          ccdbench_create,                                                               \
                                          ccdbench_destroy,                                                              \
                                          ccdbench_vertex_face,                                                          \
                                          ccdbench_edge_edge,                                                            \
                                          ccdbench_begin,                                                                \
                                          ccdbench_step,                                                                 \
                                          ccdbench_end};                                                                 \
  }                                                                                                                      \
  extern "C" CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(uint32_t host_abi_version) {            \
    return host_abi_version == CCDBENCH_PLUGIN_ABI_VERSION ? &ccdbench_table : nullptr;                                  \
  }

#endif /* CCDBENCH_PLUGIN_HPP */
