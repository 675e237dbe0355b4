/* The sub-boxes of (t, u, v) the conservative narrow phase examines (inclusion.h), and the binary min-heap it keeps
 * them in, earliest first, over caller-owned storage (on the device, a work item's private array, or its share of
 * device memory in the deep pass). Needs a 64-bit unsigned `ccd_ulong` from its environment. */
#ifndef CCD_SHARED_SUB_BOXES_H
#define CCD_SHARED_SUB_BOXES_H

/* Where the heap's storage lives: nowhere named on the host, in a work item's private array on the device; the
 * OpenCL build of the deep pass (kernels/prelude.cl) names `global`: its sub-boxes are held in device memory, room a
 * private array has not (opencl/pipeline.hpp, kDeepSubBoxFactor). OpenCL C 1.2 has no generic pointer, so the
 * search is compiled once per address space. */
#ifndef CCD_SUB_BOX_SPACE
#define CCD_SUB_BOX_SPACE
#endif

typedef struct {
  double t0, t1, u0, u1, v0, v1;
  ccd_ulong order; /* ties broken by creation order, so the search is deterministic */
} ccd_sub_box;

static inline ccd_sub_box ccd_sub_box_make(double t0, double t1, double u0, double u1, double v0, double v1, ccd_ulong order) {
  ccd_sub_box box;
  box.t0 = t0;
  box.t1 = t1;
  box.u0 = u0;
  box.u1 = u1;
  box.v0 = v0;
  box.v1 = v1;
  box.order = order;
  return box;
}

/* Earliest first: the order of the search's priority queue (a strict total order, so every heap pops alike). Among
 * boxes that start at the same time the newest comes first: the search then goes deep where it can (splits in u and
 * v keep t0), as a depth-first search would, instead of widening a front of equal boxes along a near contact. */
static inline int ccd_earlier(const CCD_SUB_BOX_SPACE ccd_sub_box* a, const CCD_SUB_BOX_SPACE ccd_sub_box* b) {
  return a->t0 != b->t0 ? a->t0 < b->t0 : a->order > b->order;
}

/* A binary min-heap of sub-boxes, earliest on top, over caller-owned storage. */
static inline void ccd_heap_sift_down(CCD_SUB_BOX_SPACE ccd_sub_box* heap, int size, int i) {
  for (;;) {
    const int left = 2 * i + 1, right = left + 1;
    int least = i;
    if (left < size && ccd_earlier(&heap[left], &heap[least])) least = left;
    if (right < size && ccd_earlier(&heap[right], &heap[least])) least = right;
    if (least == i) return;
    const ccd_sub_box swap = heap[i];
    heap[i] = heap[least];
    heap[least] = swap;
    i = least;
  }
}
static inline void ccd_heap_push(CCD_SUB_BOX_SPACE ccd_sub_box* heap, int* size, ccd_sub_box box) {
  int i = (*size)++;
  heap[i] = box;
  while (i > 0) {
    const int parent = (i - 1) / 2;
    if (!ccd_earlier(&heap[i], &heap[parent])) return;
    const ccd_sub_box swap = heap[i];
    heap[i] = heap[parent];
    heap[parent] = swap;
    i = parent;
  }
}
static inline ccd_sub_box ccd_heap_pop(CCD_SUB_BOX_SPACE ccd_sub_box* heap, int* size) {
  const ccd_sub_box top = heap[0];
  heap[0] = heap[--*size];
  ccd_heap_sift_down(heap, *size, 0);
  return top;
}

#endif
