/* Every stage of a full-traversal step (strategies/opencl/full_opencl.cpp): swept, widened boxes; the refit of
 * each object's hierarchy; traversal into candidate triangle pairs; their expansion by the assignment masks into
 * elementary pairs with the primitive-level box test; the narrow phases; and the compaction of what collides.
 * Each stage computes exactly what the CPU's `full` computes (strategies/bvh, strategies/elementary_tests.cpp),
 * with the same operations where a rounding happens (the box widening), so both report the same set.
 *
 * Lists of unknown length (candidates, elementary pairs, collisions) are filled by work groups that reserve room
 * with one atomic each (ccd_group_reserve) and write only within `capacity`; the host reads the total, and when it
 * exceeds the capacity grows the buffer and runs the stage again. Positions are 3 doubles per vertex; boxes are 6
 * doubles (min xyz, max xyz). */

#include "strategies/narrowphase/shared/geometry.h"
#include "strategies/narrowphase/shared/inclusion.h"

/* Constants the host defines from their one definition there (opencl::kernel_defines, pipeline.cpp):
 * CCD_BOX_ROUNDING_MARGIN, bvh.hpp's relative room for the rounding of widened boxes; CCD_TRAVERSAL_STACK, the depth
 * of the traversal stack (the host refuses a deeper tree before any launch); CCD_VERTEX_FACE, an elementary pair's
 * kind in the third component of its uint4: vertex-face pairs are (v, f, CCD_VERTEX_FACE, 0), edge-edge pairs
 * (a.v0, a.v1, b.v0, b.v1), vertex ids that are never CCD_VERTEX_FACE. */
#if !defined(CCD_BOX_ROUNDING_MARGIN) || !defined(CCD_TRAVERSAL_STACK) || !defined(CCD_VERTEX_FACE)
#error "CCD_BOX_ROUNDING_MARGIN, CCD_TRAVERSAL_STACK and CCD_VERTEX_FACE must be defined by the host (kernel_defines)"
#endif

typedef struct {
  double lo[3], hi[3];
} ccd_box;

static inline ccd_box ccd_box_load(global const double* boxes, uint i) {
  ccd_box b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = boxes[6 * (size_t)i + k];
    b.hi[k] = boxes[6 * (size_t)i + 3 + k];
  }
  return b;
}
static inline void ccd_box_store(global double* boxes, uint i, ccd_box b) {
  for (int k = 0; k < 3; ++k) {
    boxes[6 * (size_t)i + k] = b.lo[k];
    boxes[6 * (size_t)i + 3 + k] = b.hi[k];
  }
}
/* Eigen's empty AlignedBox: min = the largest double, max = the lowest. */
static inline ccd_box ccd_box_empty(void) {
  ccd_box b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = DBL_MAX;
    b.hi[k] = -DBL_MAX;
  }
  return b;
}
static inline ccd_box ccd_box_extend(ccd_box b, global const double* x, uint v) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = ccd_min(b.lo[k], x[3 * (size_t)v + k]);
    b.hi[k] = ccd_max(b.hi[k], x[3 * (size_t)v + k]);
  }
  return b;
}
static inline ccd_box ccd_box_merge(ccd_box a, ccd_box b) {
  for (int k = 0; k < 3; ++k) {
    a.lo[k] = ccd_min(a.lo[k], b.lo[k]);
    a.hi[k] = ccd_max(a.hi[k], b.hi[k]);
  }
  return a;
}
/* bvh.hpp's widened(): each corner moves out by ((|c| + w)·margin + w) + the smallest subnormal. */
static inline ccd_box ccd_box_widen(ccd_box b, double w) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = b.lo[k] - (((fabs(b.lo[k]) + w) * CCD_BOX_ROUNDING_MARGIN + w) + CCD_DENORM_MIN);
    b.hi[k] = b.hi[k] + (((fabs(b.hi[k]) + w) * CCD_BOX_ROUNDING_MARGIN + w) + CCD_DENORM_MIN);
  }
  return b;
}
static inline int ccd_box_intersects(ccd_box a, ccd_box b) {
  return a.lo[0] <= b.hi[0] && a.lo[1] <= b.hi[1] && a.lo[2] <= b.hi[2] && b.lo[0] <= a.hi[0] && b.lo[1] <= a.hi[1] && b.lo[2] <= a.hi[2];
}

/* Reserves `count` slots of a global list for the calling work item and returns its first one: the group sums its
 * counts in local memory (scratch: CCD_GROUP_SIZE + 1 uints) and reserves once with one atomic on total[0].
 * total[1] is set when total[0] wraps past 2^32 (the host then refuses the step). Every item of the group calls it. */
static inline uint ccd_group_reserve(local uint* scratch, uint count, volatile global uint* total) {
  const uint lid = get_local_id(0);
  scratch[lid] = count;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint offset = 1; offset < CCD_GROUP_SIZE; offset <<= 1) {
    const uint add = lid >= offset ? scratch[lid - offset] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == CCD_GROUP_SIZE - 1) {
    const uint sum = scratch[lid];
    const uint old = atomic_add(&total[0], sum);
    if (old > 0xFFFFFFFFu - sum) atomic_or(&total[1], 1u);
    scratch[CCD_GROUP_SIZE] = old;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return scratch[CCD_GROUP_SIZE] + scratch[lid] - count;
}

/* Face f's corners at t = 0 and 1 (bvh.cpp's swept_face_box before its widening). */
static inline ccd_box ccd_swept_face_box(global const uint* faces, uint f, global const double* x0, global const double* x1) {
  ccd_box b = ccd_box_empty();
  for (int k = 0; k < 3; ++k) {
    const uint v = faces[3 * (size_t)f + k];
    b = ccd_box_extend(b, x0, v);
    b = ccd_box_extend(b, x1, v);
  }
  return b;
}

/* Swept vertex boxes x0 ∪ x1 widened by half_thickness (elementary_tests.cpp's primitive-level box test). */
kernel void vertex_boxes(uint count, global const double* x0, global const double* x1, double half_thickness, global double* boxes) {
  const uint v = get_global_id(0);
  if (v >= count) return;
  ccd_box b;
  for (int k = 0; k < 3; ++k) b.lo[k] = b.hi[k] = x0[3 * (size_t)v + k];
  b = ccd_box_extend(b, x1, v);
  ccd_box_store(boxes, v, ccd_box_widen(b, half_thickness));
}

/* Leaf boxes of the listed leaves: the face's corners at t = 0 and 1, widened by `inflation` (bvh.cpp's
 * swept_face_box), plus, with has_budget, the largest budget of its corners (apccd's session trees:
 * inflation = δ/2 + max(budget[a], budget[b], budget[c]), one rounding as on the host). */
kernel void leaf_boxes(uint count, global const uint* leaves, global const uint* node_face, global const uint* faces, global const double* x0,
                       global const double* x1, double inflation, uchar has_budget, global const double* budget, global double* node_boxes) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const uint node = leaves[i];
  const uint f = node_face[node];
  const ccd_box b = ccd_swept_face_box(faces, f, x0, x1);
  double widening = inflation;
  if (has_budget) {
    widening = inflation + ccd_max(ccd_max(budget[faces[3 * (size_t)f]], budget[faces[3 * (size_t)f + 1]]), budget[faces[3 * (size_t)f + 2]]);
  }
  ccd_box_store(node_boxes, node, ccd_box_widen(b, widening));
}

/* One level of the bottom-up refit: each internal node level[first + i] becomes the union of its children. */
kernel void refit_level(uint count, uint first, global const uint* level, global const int2* children, global double* node_boxes) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const uint node = level[first + i];
  const int2 c = children[node];
  ccd_box_store(node_boxes, node, ccd_box_merge(ccd_box_load(node_boxes, (uint)c.x), ccd_box_load(node_boxes, (uint)c.y)));
}

/* Levels [first, end) of a refit in one work group, in order (deepest first): level l is the nodes
 * level[offsets[l] .. offsets[l + 1]), each the union of its children; the barrier makes a level's boxes visible to
 * the whole group before the level above reads them. The same unions as refit_level, launched once for the levels
 * too small to fill the device. */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void refit_levels_in_group(uint first, uint end, global const uint* offsets,
                                                                                              global const uint* level, global const int2* children,
                                                                                              global double* node_boxes) {
  for (uint l = first; l < end; ++l) {
    for (uint i = offsets[l] + get_local_id(0); i < offsets[l + 1]; i += CCD_GROUP_SIZE) {
      const uint node = level[i];
      const int2 c = children[node];
      ccd_box_store(node_boxes, node, ccd_box_merge(ccd_box_load(node_boxes, (uint)c.x), ccd_box_load(node_boxes, (uint)c.y)));
    }
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
}

/* Candidate triangle pairs: query q is face q_face[q] (its leaf q_leaf[q]) against the tree rooted at q_root[q].
 * Modes: 1 self (keeps the faces g > f, each pair once); 4 a face against its own tree (keeps g != f: apccd's
 * partial traversal, whose query box is not the leaf's); 0 a pair of objects; 2 and 3 a pair of objects in moving
 * frames (apccd's object_pairs=session), whose translation box offsets[6 q_offset[q]] sweeps the query's box (2)
 * or every box of the tree (3), as bvh.cpp's shifted(): (lo + offset lo, hi + offset hi). Pairs are written as
 * (smaller, larger). Exactly the face pairs whose leaf boxes overlap (after the sweep): an internal box holds its
 * leaves' boxes, and a swept one its leaves' swept boxes (rounding is monotone), so pruning loses none. The walk
 * that counts keeps the first CCD_TRAVERSAL_KEEP faces it finds in the work item's own memory; a query that found
 * no more writes them from there, and only one that found more walks its tree again to write (issue 36: the second
 * walk was about half of the traversal's time). Either way the pairs are written in the order of the walk. A self
 * query skips, before loading its box, a subtree whose faces are all at most f (max_face: the largest face of each
 * node's subtree): it would keep none of them, and each pair is found once, from its smaller face. */
#define CCD_TRAVERSAL_KEEP 32
static inline ccd_box ccd_box_shift(ccd_box b, global const double* offset) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = b.lo[k] + offset[k];
    b.hi[k] = b.hi[k] + offset[3 + k];
  }
  return b;
}
static inline uint ccd_traverse(uint f, ccd_box query, int root, int mode, global const double* offset, global const double* node_boxes,
                                global const int2* children, global const uint* node_face, global const uint* max_face, global uint2* pairs,
                                uint first, uint capacity, int write, uint* kept) {
  int stack[CCD_TRAVERSAL_STACK];
  int size = 0;
  uint found = 0;
  stack[size++] = root;
  while (size > 0) {
    const int node = stack[--size];
    if (mode == 1 && max_face[node] <= f) continue;
    const ccd_box box = mode == 3 ? ccd_box_shift(ccd_box_load(node_boxes, (uint)node), offset) : ccd_box_load(node_boxes, (uint)node);
    if (!ccd_box_intersects(query, box)) continue;
    const int2 c = children[node];
    if (c.x >= 0) {
      stack[size++] = c.x;
      stack[size++] = c.y;
      continue;
    }
    const uint g = node_face[node];
    if (mode == 1 ? g > f : (mode == 4 ? g != f : 1)) {
      if (write && first + found < capacity) pairs[first + found] = (uint2)(min(f, g), max(f, g));
      if (!write && found < CCD_TRAVERSAL_KEEP) kept[found] = g;
      ++found;
    }
  }
  return found;
}

/* The pairs of face f with the `found` (at most CCD_TRAVERSAL_KEEP) faces a counting walk kept, as the writing walk
 * writes them. */
static inline void ccd_write_kept(uint f, const uint* kept, uint found, global uint2* pairs, uint first, uint capacity) {
  for (uint j = 0; j < found && first + j < capacity; ++j) pairs[first + j] = (uint2)(min(f, kept[j]), max(f, kept[j]));
}

kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void traverse(uint count, global const uint* q_leaf, global const uint* q_face,
                                                                                 global const int* q_root, global const uchar* q_mode,
                                                                                 global const int* q_offset, global const double* offsets,
                                                                                 global const double* node_boxes, global const int2* children,
                                                                                 global const uint* node_face, global const uint* max_face,
                                                                                 uint capacity, volatile global uint* total, global uint2* pairs) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  uint kept[CCD_TRAVERSAL_KEEP];
  const uint q = get_global_id(0);
  uint found = 0;
  ccd_box query;
  int mode = 0;
  global const double* offset = offsets;
  if (q < count) {
    mode = q_mode[q];
    if (mode >= 2) offset = offsets + 6 * (size_t)q_offset[q];
    query = ccd_box_load(node_boxes, q_leaf[q]);
    if (mode == 2) query = ccd_box_shift(query, offset);
    found = ccd_traverse(q_face[q], query, q_root[q], mode, offset, node_boxes, children, node_face, max_face, pairs, 0, 0, 0, kept);
  }
  const uint first = ccd_group_reserve(scratch, found, total);
  if (q < count && found > 0 && first < capacity) {
    if (found <= CCD_TRAVERSAL_KEEP) {
      ccd_write_kept(q_face[q], kept, found, pairs, first, capacity);
    } else {
      ccd_traverse(q_face[q], query, q_root[q], mode, offset, node_boxes, children, node_face, max_face, pairs, first, capacity, 1, kept);
    }
  }
}

static inline int ccd_corner_of(uint v, uint3 face) { return v == face.x || v == face.y || v == face.z; }
static inline uint3 ccd_face(global const uint* faces, uint f) {
  return (uint3)(faces[3 * (size_t)f], faces[3 * (size_t)f + 1], faces[3 * (size_t)f + 2]);
}
static inline uint ccd_face_corner(uint3 face, int k) { return k == 0 ? face.x : (k == 1 ? face.y : face.z); }
static inline ccd_box ccd_vertex_box(global const double* vertex_boxes, uint v) { return ccd_box_load(vertex_boxes, v); }

/* The elementary pairs of candidate (a, b), as elementary_tests.cpp generates them: the vertices each face owns
 * against the other face, then the edges a owns against those b owns; skipping pairs that share a vertex and pairs
 * whose swept, widened primitive boxes are apart. Into `pairs` (at most 15: 6 vertex-face, 9 edge-edge, all of them
 * kept in the work item's own memory, so that the pairs are found once and written after the group's reservation). */
static inline uint ccd_expand(uint a, uint b, global const uchar* masks, global const uint* faces, global const uint* face_edges,
                              global const uint2* edges, global const double* vertex_boxes, uint4* pairs) {
  uint found = 0;
  for (int side = 0; side < 2; ++side) {
    const uint owner = side == 0 ? a : b, other = side == 0 ? b : a;
    const uint3 owner_face = ccd_face(faces, owner), other_face = ccd_face(faces, other);
    const ccd_box face_box = ccd_box_merge(
        ccd_box_merge(ccd_box_merge(ccd_box_empty(), ccd_vertex_box(vertex_boxes, other_face.x)), ccd_vertex_box(vertex_boxes, other_face.y)),
        ccd_vertex_box(vertex_boxes, other_face.z));
    for (int k = 0; k < 3; ++k) {
      if (!(masks[owner] & (1u << k))) continue;
      const uint v = ccd_face_corner(owner_face, k);
      if (ccd_corner_of(v, other_face) || !ccd_box_intersects(ccd_vertex_box(vertex_boxes, v), face_box)) continue;
      pairs[found++] = (uint4)(v, other, CCD_VERTEX_FACE, 0u);
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (!(masks[a] & (1u << (3 + i)))) continue;
    const uint2 ea = edges[face_edges[3 * (size_t)a + i]];
    const ccd_box box_a = ccd_box_merge(ccd_box_merge(ccd_box_empty(), ccd_vertex_box(vertex_boxes, ea.x)), ccd_vertex_box(vertex_boxes, ea.y));
    for (int j = 0; j < 3; ++j) {
      if (!(masks[b] & (1u << (3 + j)))) continue;
      const uint2 eb = edges[face_edges[3 * (size_t)b + j]];
      if (ea.x == eb.x || ea.x == eb.y || ea.y == eb.x || ea.y == eb.y) continue;
      const ccd_box box_b = ccd_box_merge(ccd_box_merge(ccd_box_empty(), ccd_vertex_box(vertex_boxes, eb.x)), ccd_vertex_box(vertex_boxes, eb.y));
      if (!ccd_box_intersects(box_a, box_b)) continue;
      /* make_edge_edge_pair: the smaller edge (by v0, then v1) first */
      const int a_first = ea.x < eb.x || (ea.x == eb.x && ea.y < eb.y);
      pairs[found++] = a_first ? (uint4)(ea.x, ea.y, eb.x, eb.y) : (uint4)(eb.x, eb.y, ea.x, ea.y);
    }
  }
  return found;
}

kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void expand(uint count, global const uint2* candidates, global const uchar* masks,
                                                                               global const uint* faces, global const uint* face_edges,
                                                                               global const uint2* edges, global const double* vertex_boxes,
                                                                               uint capacity, volatile global uint* total, global uint4* out) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  uint4 pairs[15];
  const uint i = get_global_id(0);
  uint found = 0;
  if (i < count) {
    const uint2 pair = candidates[i];
    found = ccd_expand(pair.x, pair.y, masks, faces, face_edges, edges, vertex_boxes, pairs);
  }
  const uint first = ccd_group_reserve(scratch, found, total);
  for (uint j = 0; j < found && first + j < capacity; ++j) out[first + j] = pairs[j];
}

/* The pair's eight rows (step.hpp's pair_rows). */
static inline int ccd_load_rows(uint4 p, global const uint* faces, global const double* x0, global const double* x1, ccd_v3 rows[8]) {
  const int vertex_face = p.z == CCD_VERTEX_FACE;
  uint ids[4];
  if (vertex_face) {
    ids[0] = p.x;
    ids[1] = faces[3 * (size_t)p.y];
    ids[2] = faces[3 * (size_t)p.y + 1];
    ids[3] = faces[3 * (size_t)p.y + 2];
  } else {
    ids[0] = p.x;
    ids[1] = p.y;
    ids[2] = p.z;
    ids[3] = p.w;
  }
  for (int k = 0; k < 4; ++k) {
    rows[k] = ccd_v3_make(x0[3 * (size_t)ids[k]], x0[3 * (size_t)ids[k] + 1], x0[3 * (size_t)ids[k] + 2]);
    rows[k + 4] = ccd_v3_make(x1[3 * (size_t)ids[k]], x1[3 * (size_t)ids[k] + 1], x1[3 * (size_t)ids[k] + 2]);
  }
  return vertex_face;
}

#ifndef CCD_DEEP_PASS
/* status: 0 apart, 1 collides (toi set), 2 the query needs more than give_up_after iterations (a later device pass
 * decides it), 3 more sub-boxes than a work item holds (the deep pass decides it). */
kernel void narrow_conservative(uint count, global const uint4* pairs, global const uint* faces, global const double* x0, global const double* x1,
                                double thickness, double tolerance, double toi_tolerance, long max_iterations, long give_up_after,
                                global uchar* status, global double* toi) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  ccd_v3 rows[8];
  const int vertex_face = ccd_load_rows(pairs[i], faces, x0, x1, rows);
  ccd_sub_box storage[CCD_DEVICE_SUB_BOXES];
  const ccd_conservative_outcome r =
      ccd_conservative_test(rows, thickness, vertex_face, tolerance, toi_tolerance, max_iterations, give_up_after, storage, CCD_DEVICE_SUB_BOXES);
  status[i] = r.overflow ? (uchar)(r.gave_up ? 2 : 3) : (uchar)(r.collides ? 1 : 0);
  toi[i] = r.toi;
}
#else
/* The queries that overflowed a work item's sub-boxes, each with `capacity` sub-boxes of its own in `sub_boxes`
 * (device memory) and no limit on its iterations but the narrow phase's cap; status as above, 3 where even these
 * overflow (the host decides it). */
kernel void narrow_conservative_deep(uint count, global const uint4* pairs, global const uint* faces, global const double* x0,
                                     global const double* x1, double thickness, double tolerance, double toi_tolerance, long max_iterations,
                                     global ccd_sub_box* sub_boxes, uint capacity, global uchar* status, global double* toi) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  ccd_v3 rows[8];
  const int vertex_face = ccd_load_rows(pairs[i], faces, x0, x1, rows);
  const ccd_conservative_outcome r = ccd_conservative_test(rows, thickness, vertex_face, tolerance, toi_tolerance, max_iterations, 0,
                                                           sub_boxes + (size_t)i * capacity, (int)capacity);
  status[i] = r.overflow ? (uchar)3 : (uchar)(r.collides ? 1 : 0);
  toi[i] = r.toi;
}
#endif

#ifndef CCD_DEEP_PASS /* (the deep pass's build holds the conservative search alone: it compiles in half the time) */
kernel void narrow_cubic(uint count, global const uint4* pairs, global const uint* faces, global const double* x0, global const double* x1,
                         double thickness, double eta, global uchar* status, global double* toi) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  ccd_v3 rows[8];
  const int vertex_face = ccd_load_rows(pairs[i], faces, x0, x1, rows);
  const ccd_cubic_outcome r = ccd_cubic_test(rows, thickness, eta, vertex_face);
  status[i] = (uchar)(r.collides ? 1 : 0);
  toi[i] = r.toi;
}
#endif

/* The pairs whose status is not 0, with their status and TOI (in any order: the host sorts). */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void compact(uint count, global const uint4* pairs, global const uchar* status,
                                                                                global const double* toi, uint capacity, volatile global uint* total,
                                                                                global uint4* out_pairs, global uchar* out_status,
                                                                                global double* out_toi) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  const uint i = get_global_id(0);
  const uint keep = i < count && status[i] != 0 ? 1u : 0u;
  const uint slot = ccd_group_reserve(scratch, keep, total);
  if (keep && slot < capacity) {
    out_pairs[slot] = pairs[i];
    out_status[slot] = status[i];
    out_toi[slot] = toi[i];
  }
}
