/* apccd's own stages on the device (strategies/apccd/opencl/apccd_opencl.cpp); the refit, traversal, expansion and
 * narrow phases are full.cl's. Each computes what the CPU's apccd computes, with the same operations where a
 * rounding happens (a relative position is one subtraction per coordinate, a widened box as bvh.cpp's), so that
 * both backends test the same pairs. */

#ifndef CCD_DEEP_PASS /* (none of apccd's stages in the deep pass's build, prelude.cl) */
#include "strategies/narrowphase/shared/geometry.h"
#include "strategies/narrowphase/shared/separation.h"

/* CCD_EMPTY_KEY, an empty slot of the pending list's hash table (no pair key is all ones: a pair is (a, b) with
 * a < b), comes from the host, which fills the table with it (opencl::kernel_defines). */
#ifndef CCD_EMPTY_KEY
#error "CCD_EMPTY_KEY must be defined by the host (kernel_defines)"
#endif

/* Positions in each object's frame: x - centroid[object of the vertex] (static objects: centroid 0). */
kernel void object_frame(uint count, global const double* x, global const uint* vertex_object, global const double* centroids,
                         global double* relative) {
  const uint v = get_global_id(0);
  if (v >= count) return;
  const uint o = vertex_object[v];
  for (int k = 0; k < 3; ++k) relative[3 * (size_t)v + k] = x[3 * (size_t)v + k] - centroids[3 * (size_t)o + k];
}

/* |relative - anchor|_inf > budget (the CPU's `outside`: cwiseAbs().maxCoeff(), max(max(x, y), z)). */
static inline int ccd_outside(global const double* relative, global const double* anchor, uint v, double budget) {
  const ccd_v3 d = ccd_v3_make(relative[3 * (size_t)v] - anchor[3 * (size_t)v], relative[3 * (size_t)v + 1] - anchor[3 * (size_t)v + 1],
                               relative[3 * (size_t)v + 2] - anchor[3 * (size_t)v + 2]);
  return ccd_max_coeff(ccd_cwise_abs(d)) > budget;
}

/* Dangling vertices: beyond their budget around the session's anchor at either end of the step; counted in total[0]. */
kernel void dangling_vertices(uint count, global const double* relative0, global const double* relative1, global const double* anchor,
                              global const double* budget, global uchar* dangling, volatile global uint* total) {
  const uint v = get_global_id(0);
  if (v >= count) return;
  const int out = ccd_outside(relative0, anchor, v, budget[v]) || ccd_outside(relative1, anchor, v, budget[v]);
  dangling[v] = (uchar)out;
  if (out) atomic_inc(&total[0]);
}

/* Dangling triangles: the faces with a dangling corner, listed in any order. */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void dangling_faces(uint count, global const uint* faces,
                                                                                       global const uchar* dangling, uint capacity,
                                                                                       volatile global uint* total, global uint* out) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  const uint f = get_global_id(0);
  const uint keep =
      f < count && (dangling[faces[3 * (size_t)f]] || dangling[faces[3 * (size_t)f + 1]] || dangling[faces[3 * (size_t)f + 2]]) ? 1u : 0u;
  const uint slot = ccd_group_reserve(scratch, keep, total);
  if (keep && slot < capacity) out[slot] = f;
}

/* Each dangling face's fresh box (relative positions over the step, widened by δ/2), kept for its query, and its
 * leaf grown to hold it (the CPU's enlarge_leaf; the levels above are refitted after). */
kernel void enlarge_leaves(uint count, global const uint* dangling, global const uint* leaf_node, global const uint* faces,
                           global const double* relative0, global const double* relative1, double half_thickness, global double* node_boxes,
                           global double* fresh_boxes) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const uint f = dangling[i];
  const ccd_box fresh = ccd_box_widen(ccd_swept_face_box(faces, f, relative0, relative1), half_thickness);
  ccd_box_store(fresh_boxes, i, fresh);
  const uint leaf = leaf_node[f];
  ccd_box_store(node_boxes, leaf, ccd_box_merge(ccd_box_load(node_boxes, leaf), fresh));
}

/* The partial traversal: each dangling face's fresh box against its own object's tree (face_root[f] < 0: the
 * object has no self-collision), every other face whose leaf overlaps it, as (smaller, larger). */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void partial_traverse(
    uint count, global const uint* dangling, global const double* fresh_boxes, global const int* face_root, global const double* node_boxes,
    global const int2* children, global const uint* node_face, uint capacity, volatile global uint* total, global uint2* pairs) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  uint kept[CCD_TRAVERSAL_KEEP];
  const uint i = get_global_id(0);
  uint found = 0;
  uint f = 0;
  int root = -1;
  ccd_box query;
  if (i < count) {
    f = dangling[i];
    root = face_root[f];
    query = ccd_box_load(fresh_boxes, i);
    if (root >= 0)
      found =
          ccd_traverse(f, query, root, 4, /* no offset */ node_boxes, node_boxes, children, node_face, /* mode 4: unused */ 0, pairs, 0, 0, 0, kept);
  }
  const uint first = ccd_group_reserve(scratch, found, total);
  if (found > 0 && first < capacity) {
    if (found <= CCD_TRAVERSAL_KEEP) {
      ccd_write_kept(f, kept, found, pairs, first, capacity);
    } else {
      ccd_traverse(f, query, root, 4, node_boxes, node_boxes, children, node_face, 0, pairs, first, capacity, 1, kept);
    }
  }
}

#ifdef cl_khr_int64_base_atomics /* a device without it still runs full.cl; apccd refuses it on the host */
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
/* The pending list's hash table (open addressing, linear probing, 2^bits slots of 64-bit keys (a << 32) | b):
 * inserts each pair; with `append`, a pair not there before is also appended to the pending list after its
 * first `pending_first` entries (total[0] counts them). The set that results does not depend on the order. */
kernel void pending_insert(uint count, global const uint2* pairs, volatile global ulong* table, uint bits, uchar append, global uint2* pending,
                           uint pending_first, volatile global uint* total) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const uint2 p = pairs[i];
  const ulong key = ((ulong)p.x << 32) | (ulong)p.y;
  const ulong mask = (((ulong)1) << bits) - 1;
  ulong slot = (key * 0x9E3779B97F4A7C15UL) >> (64 - bits); /* Fibonacci hashing: the top bits of the product */
  while (1) {
    const ulong old = atom_cmpxchg(&table[slot], CCD_EMPTY_KEY, key);
    if (old == CCD_EMPTY_KEY) {
      if (append) pending[pending_first + atomic_inc(&total[0])] = p;
      return;
    }
    if (old == key) return;
    slot = (slot + 1) & mask;
  }
}
#endif

/* Each face's fresh swept box in world coordinates, widened by δ/2 (the front end's boxes). */
kernel void face_boxes(uint count, global const uint* faces, global const double* x0, global const double* x1, double half_thickness,
                       global double* boxes) {
  const uint f = get_global_id(0);
  if (f >= count) return;
  ccd_box_store(boxes, f, ccd_box_widen(ccd_swept_face_box(faces, f, x0, x1), half_thickness));
}

/* The front end: the pairs of the pending list and of this step's object pairs whose faces' fresh boxes overlap
 * (every pair with check = 0: heuristic=off). */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void admit(uint count_a, global const uint2* a, uint count_b,
                                                                              global const uint2* b, global const double* boxes, uchar check,
                                                                              uint capacity, volatile global uint* total, global uint2* out) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  const uint i = get_global_id(0);
  uint keep = 0;
  uint2 p = (uint2)(0u, 0u);
  if (i < count_a + count_b) {
    p = i < count_a ? a[i] : b[i - count_a];
    keep = !check || ccd_box_intersects(ccd_box_load(boxes, p.x), ccd_box_load(boxes, p.y)) ? 1u : 0u;
  }
  const uint slot = ccd_group_reserve(scratch, keep, total);
  if (keep && slot < capacity) out[slot] = p;
}

/* The distance heuristic: keep[i] = 0 when the separation filter proves the pair farther apart than δ. */
kernel void separation(uint count, global const uint4* pairs, global const uint* faces, global const double* x0, global const double* x1,
                       double thickness, global uchar* keep) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  ccd_v3 rows[8];
  const int vertex_face = ccd_load_rows(pairs[i], faces, x0, x1, rows);
  keep[i] = ccd_provably_apart(rows, vertex_face, thickness) ? (uchar)0 : (uchar)1;
}

/* The pairs with keep != 0, in any order. */
kernel __attribute__((reqd_work_group_size(CCD_GROUP_SIZE, 1, 1))) void compact_kept(uint count, global const uint4* pairs, global const uchar* keep,
                                                                                     uint capacity, volatile global uint* total, global uint4* out) {
  local uint scratch[CCD_GROUP_SIZE + 1];
  const uint i = get_global_id(0);
  const uint k = i < count && keep[i] != 0 ? 1u : 0u;
  const uint slot = ccd_group_reserve(scratch, k, total);
  if (k && slot < capacity) out[slot] = pairs[i];
}
#endif
