/* ccdbench's plugin ABI: how a continuous collision detection method of your own, in any language that can export
 * C functions, is judged by ccdbench like its built-in methods (docs/audit.md).
 *
 * A plugin is a shared library that exports one function, CCDBENCH_PLUGIN_ENTRY (ccdbench_plugin_init_v1). ccdbench
 * loads it with dlopen, calls it with the ABI version it speaks, and reads the table it returns. The table starts
 * with its own size and ABI version, so that a later ABI can add fields at its end without breaking plugins built
 * for an earlier one; a plugin built for another ABI version is refused, naming both versions.
 *
 * What a plugin can answer (one or both):
 *  - per query: whether a vertex-face or edge-edge pair with linear motion over a step comes within a distance
 *    thickness of touching at some t in [0, 1], and when first. ccdbench then uses it as a narrow phase
 *    (`queries --method plugin:PATH`, `stress --method plugin:PATH`, `run --strategy full+plugin:PATH`);
 *  - per step: every colliding vertex-face and edge-edge pair of a whole mesh over a step, with its time of impact
 *    (`run --strategy plugin:PATH`), with a context kept from step to step (a session, a cache).
 *
 * Conventions:
 *  - Positions are plain doubles. A query's 24 doubles are 8 points of 3 coordinates, in Tight-Inclusion's order:
 *    vertex-face: v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1 (the vertex, then the face's corners, at
 *    t = 0 then t = 1); edge-edge: ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1.
 *  - A time of impact is a fraction of the step in [0, 1]; a conservative method reports one never later than the
 *    earliest contact.
 *  - Every string a plugin hands over (names, keys, messages) is UTF-8 and stays valid until the plugin is unloaded,
 *    except messages, which the plugin writes into the buffer it is given.
 *  - ccdbench checks every answer: a TOI that is not a number in [0, 1], an index out of range, a pair that shares a
 *    vertex or that the scene does not let collide, and a pair reported twice are the plugin's errors, counted and
 *    shown as such, never taken as answers.
 */
#ifndef CCDBENCH_PLUGIN_H
#define CCDBENCH_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The ABI this header describes. ccdbench refuses a plugin whose table says another. */
#define CCDBENCH_PLUGIN_ABI_VERSION 1u

/* The function every plugin exports: given the ABI version ccdbench speaks, the plugin's table (or NULL when it
 * cannot serve that version). */
#define CCDBENCH_PLUGIN_ENTRY ccdbench_plugin_init_v1
#define CCDBENCH_PLUGIN_ENTRY_NAME "ccdbench_plugin_init_v1"
/* Put before the entry point's definition: it stays exported when the rest of the plugin is built hidden. */
#define CCDBENCH_PLUGIN_EXPORT __attribute__((visibility("default")))

/* Capability flags (ccdbench_plugin.capabilities). */
#define CCDBENCH_THREAD_SAFE 1u  /* its query functions may be called from several threads at once on one context */
#define CCDBENCH_REPORTS_TOI 2u  /* a contact comes with its time of impact (else "yes" or "no" only) */
#define CCDBENCH_CONSERVATIVE 4u /* claims never to miss a contact: ccdbench then gates it on 0 misses */

/* A key a user may set on the command line (plugin:PATH:name=value). */
enum ccdbench_key_kind { CCDBENCH_KEY_NUMBER = 0, CCDBENCH_KEY_INTEGER = 1, CCDBENCH_KEY_CHOICE = 2, CCDBENCH_KEY_TEXT = 3 };
typedef struct ccdbench_key {
  const char* name;          /* letters, digits and '_' */
  int kind;                  /* enum ccdbench_key_kind */
  const char* default_value; /* as text, within the values below */
  double minimum, maximum;   /* NUMBER and INTEGER: the values it accepts */
  const char* choices;       /* CHOICE: the values it accepts, separated by '|' ("on|off") */
  const char* help;          /* one line */
} ccdbench_key;

/* What a query's answer is. An error is its own outcome: ccdbench counts it apart (and, for the gate, as its
 * `errors` key says: a miss by default), never as a contact. */
enum ccdbench_outcome { CCDBENCH_APART = 0, CCDBENCH_CONTACT = 1, CCDBENCH_UNDECIDED = 2, CCDBENCH_ERROR = 3 };

#define CCDBENCH_MESSAGE_SIZE 256
typedef struct ccdbench_answer {
  int outcome;                         /* enum ccdbench_outcome */
  double toi;                          /* CONTACT with CCDBENCH_REPORTS_TOI: the time of impact in [0, 1] */
  char message[CCDBENCH_MESSAGE_SIZE]; /* UNDECIDED or ERROR: why (ccdbench shows it) */
} ccdbench_answer;

/* The mesh a whole-step plugin works on, handed over once before the first step (`begin`). Vertex, face and edge
 * indices are 0-based. A pair may collide when its two primitives' objects are one object with self-collision on,
 * or two objects listed as collidable. Edges are the mesh's, each (v0, v1) with v0 < v1. */
typedef struct ccdbench_scene {
  size_t vertex_count;
  size_t face_count;
  const uint32_t* faces; /* 3 vertex indices per face */
  size_t edge_count;
  const uint32_t* edges; /* 2 vertex indices per edge */
  size_t object_count;
  const uint32_t* face_object;          /* the object of each face */
  const uint8_t* object_self_collision; /* 1 when the object collides with itself */
  size_t collidable_count;
  const uint32_t* collidable; /* 2 object indices per collidable pair of distinct objects */
} ccdbench_scene;

/* One step: positions at its start and end (3 doubles per vertex), in order from the first step. */
typedef struct ccdbench_step {
  size_t index;
  const double* x0;
  const double* x1;
  double thickness;
} ccdbench_step;

/* Where a whole-step plugin reports each colliding pair (toi: its time of impact, or NaN without one). */
typedef struct ccdbench_contacts {
  void* host;
  void (*vertex_face)(void* host, uint32_t vertex, uint32_t face, double toi);
  void (*edge_edge)(void* host, uint32_t a0, uint32_t a1, uint32_t b0, uint32_t b1, double toi);
} ccdbench_contacts;

typedef struct ccdbench_plugin {
  /* First, and never moved: the size of this table as the plugin was built, and the ABI it was built for. */
  size_t size;
  uint32_t abi_version;

  const char* name;      /* a short name ("naive-float") */
  const char* version;   /* the method's own version */
  const char* help;      /* one line: what it computes and what it claims */
  uint32_t capabilities; /* CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI | CCDBENCH_CONSERVATIVE */
  const ccdbench_key* keys;
  size_t key_count;

  /* A context configured with `values` (one text per key, in the table's order, every default filled in). Returns
   * NULL and writes why into `error` (CCDBENCH_MESSAGE_SIZE bytes) when it cannot. */
  void* (*create)(const char* const* values, char* error);
  void (*destroy)(void* context);

  /* Per query (NULL when the plugin has none): `rows` are 24 doubles in the order above. */
  void (*vertex_face)(void* context, const double* rows, double thickness, ccdbench_answer* answer);
  void (*edge_edge)(void* context, const double* rows, double thickness, ccdbench_answer* answer);

  /* Per step (`step` NULL when the plugin has none). `begin` once with the mesh, then `step` for every step in
   * order, then `end`; a nonzero return is an error whose message is in `error` (CCDBENCH_MESSAGE_SIZE bytes).
   * `begin` and `end` may be NULL. */
  int (*begin)(void* context, const ccdbench_scene* scene, char* error);
  int (*step)(void* context, const ccdbench_step* step, const ccdbench_contacts* contacts, char* error);
  void (*end)(void* context);
} ccdbench_plugin;

typedef const ccdbench_plugin* (*ccdbench_plugin_entry)(uint32_t host_abi_version);

#ifdef __cplusplus
}
#endif

#endif /* CCDBENCH_PLUGIN_H */
