/* naive-float: a deliberately naive CCD, as a ccdbench plugin in plain C (docs/audit.md).
 *
 * It samples the step at `samples` evenly spaced times and calls a pair colliding when, at one of them, its
 * distance in single precision is within the thickness. It misses every contact that happens between two samples
 * (a fast vertex passes through a face) and reports the sample after the contact as its TOI (late): ccdbench's
 * `queries`, `stress` and `run` show both, and `run --misses DIR` writes each missed pair as a query to replay.
 *
 * Build: cc -O2 -shared -fPIC -I PREFIX/include naive_float.c -o libnaive_float.so -lm
 */
#include <ccdbench/ccdbench_plugin.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct {
  float x, y, z;
} vec;

static vec sub(vec a, vec b) {
  vec r = {a.x - b.x, a.y - b.y, a.z - b.z};
  return r;
}
static vec add(vec a, vec b) {
  vec r = {a.x + b.x, a.y + b.y, a.z + b.z};
  return r;
}
static vec scale(vec a, float s) {
  vec r = {a.x * s, a.y * s, a.z * s};
  return r;
}
static float dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static float clamp01(float v) { return v < 0 ? 0 : (v > 1 ? 1 : v); }

/* The point of row r at time t (rows: 4 points at t = 0, then the same 4 at t = 1). */
static vec at(const double* rows, int r, float t) {
  vec p0 = {(float)rows[3 * r], (float)rows[3 * r + 1], (float)rows[3 * r + 2]};
  vec p1 = {(float)rows[3 * (r + 4)], (float)rows[3 * (r + 4) + 1], (float)rows[3 * (r + 4) + 2]};
  return add(p0, scale(sub(p1, p0), t));
}

/* The point of triangle abc closest to p (Ericson, Real-Time Collision Detection, 5.1.5). */
static vec closest_on_triangle(vec p, vec a, vec b, vec c) {
  vec ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  vec bp = sub(p, b);
  float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return add(a, scale(ab, d1 / (d1 - d3)));
  vec cp = sub(p, c);
  float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return add(a, scale(ac, d2 / (d2 - d6)));
  float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  float denom = 1.0f / (va + vb + vc);
  return add(a, add(scale(ab, vb * denom), scale(ac, vc * denom)));
}

/* Squared distance from p to triangle abc. */
static float point_triangle(vec p, vec a, vec b, vec c) {
  vec d = sub(p, closest_on_triangle(p, a, b, c));
  return dot(d, d);
}

/* Squared distance between segments p1q1 and p2q2 (Ericson 5.1.9). */
static float segment_segment(vec p1, vec q1, vec p2, vec q2) {
  vec d1 = sub(q1, p1), d2 = sub(q2, p2), r = sub(p1, p2);
  float a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r), s, t;
  if (a <= 1e-30f && e <= 1e-30f) {
    s = t = 0;
  } else if (a <= 1e-30f) {
    s = 0;
    t = clamp01(f / e);
  } else {
    float c = dot(d1, r);
    if (e <= 1e-30f) {
      t = 0;
      s = clamp01(-c / a);
    } else {
      float b = dot(d1, d2), denom = a * e - b * b;
      s = denom != 0 ? clamp01((b * f - c * e) / denom) : 0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = clamp01(-c / a);
      } else if (t > 1) {
        t = 1;
        s = clamp01((b - c) / a);
      }
    }
  }
  vec d = sub(add(p1, scale(d1, s)), add(p2, scale(d2, t)));
  return dot(d, d);
}

typedef struct {
  int samples;
} context;

static void* create(const char* const* values, char* error) {
  context* c = malloc(sizeof *c);
  if (!c) {
    snprintf(error, CCDBENCH_MESSAGE_SIZE, "out of memory");
    return NULL;
  }
  c->samples = atoi(values[0]);
  return c;
}
static void destroy(void* c) { free(c); }

static void answer(const context* c, const double* rows, double thickness, int vertex_face, ccdbench_answer* out) {
  float reach = (float)thickness;
  for (int k = 0; k < c->samples; ++k) {
    float t = c->samples == 1 ? 0.0f : (float)k / (float)(c->samples - 1);
    float d2 = vertex_face ? point_triangle(at(rows, 0, t), at(rows, 1, t), at(rows, 2, t), at(rows, 3, t))
                           : segment_segment(at(rows, 0, t), at(rows, 1, t), at(rows, 2, t), at(rows, 3, t));
    if (d2 <= reach * reach) {
      out->outcome = CCDBENCH_CONTACT;
      out->toi = t;
      return;
    }
  }
  out->outcome = CCDBENCH_APART;
}

static void vertex_face(void* c, const double* rows, double thickness, ccdbench_answer* out) { answer(c, rows, thickness, 1, out); }
static void edge_edge(void* c, const double* rows, double thickness, ccdbench_answer* out) { answer(c, rows, thickness, 0, out); }

static const ccdbench_key keys[] = {
    {"samples", CCDBENCH_KEY_INTEGER, "8", 1, 1e6, NULL, "times at which the distance is checked, evenly spaced over the step"},
};

static const ccdbench_plugin table = {
    sizeof(ccdbench_plugin),
    CCDBENCH_PLUGIN_ABI_VERSION,
    "naive-float",
    "1.0",
    "distance in float at a few sample times: misses what passes between them, and reports late TOIs",
    CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI,
    keys,
    sizeof keys / sizeof keys[0],
    create,
    destroy,
    vertex_face,
    edge_edge,
    NULL,
    NULL,
    NULL,
};

CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(uint32_t host_abi_version) {
  return host_abi_version == CCDBENCH_PLUGIN_ABI_VERSION ? &table : NULL;
}
