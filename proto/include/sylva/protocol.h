/* sylva: the messages of the wire protocol `sylva.v1` (spec/protocol.md), both
 * directions. Deterministic (the same input gives the same bytes), no I/O.
 *
 *   sylva_msg m; char err[512];
 *   if (sylva_msg_parse(text, len, &m, err, sizeof err) < 0) {
 *     char *reply = sylva_msg_error("bad_request", err, m.ref);   (m.ref may be NULL)
 *     ...
 *   }
 *   ... m.type, m.run, ...
 *   sylva_msg_free(&m);
 *
 * Encoders return compact JSON in a malloc'd NUL-terminated string (no newline),
 * NULL when out of memory. Their `ref` argument is JSON text (as in sylva_msg.ref)
 * appended as "ref":<ref> when not NULL. Positions print with 4 decimals and radii
 * with 5 (trimmed), as in the skeleton format. */
#ifndef SYLVA_PROTOCOL_H
#define SYLVA_PROTOCOL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sylva/run_status.h"
#include "sylva/scenario.h"
#include "sylva/world.h"

/** The protocol version of `sylva.v1`, sent in "welcome". */
#define SYLVA_PROTOCOL_VERSION 1
/** The WebSocket subprotocol name. */
#define SYLVA_PROTOCOL_NAME "sylva.v1"
/** Deepest JSON nesting of a client message (the outermost object is depth 1). */
#define SYLVA_MSG_MAX_DEPTH 64
/** Longest run name, bytes. */
#define SYLVA_MSG_NAME_MAX 255
/** Most plants, obstacles or obstacle removals of one "edit" (each list). */
#define SYLVA_MSG_MAX_EDIT 1000
/** Largest step count of "control". */
#define SYLVA_MSG_MAX_STEP 100000
/** Largest run id and seq (2^53 - 1: the largest integer n such that n and n + 1
 *  are exact doubles, so a larger number text can never be mistaken for it). */
#define SYLVA_MSG_ID_MAX 9007199254740991.0

/** Client message types. */
typedef enum sylva_msg_type {
  SYLVA_MSG_HELLO,
  SYLVA_MSG_LIST,
  SYLVA_MSG_CREATE,
  SYLVA_MSG_SUBSCRIBE,
  SYLVA_MSG_UNSUBSCRIBE,
  SYLVA_MSG_CONTROL,
  SYLVA_MSG_EDIT,
  SYLVA_MSG_FORK,
  SYLVA_MSG_GET,
  SYLVA_MSG_LIGHT,
  SYLVA_MSG_SCENARIOS
} sylva_msg_type;

/** The detail of a subscription (subscribe's "detail"): every node, or each stem's
 *  stats only (docs/protocol.md, "subscribe"). */
typedef enum sylva_detail {
  SYLVA_DETAIL_NODES, /**< "nodes", the default: snapshots and deltas with nodes */
  SYLVA_DETAIL_STEMS, /**< "stems": without nodes, radii, shed nodes or leaves */
  SYLVA_DETAIL_COUNT
} sylva_detail;

/** Actions of a "control" message. */
typedef enum sylva_control_action {
  SYLVA_CONTROL_START,
  SYLVA_CONTROL_PAUSE,
  SYLVA_CONTROL_STEP,
  SYLVA_CONTROL_STOP
} sylva_control_action;

/** A parsed client message. Only the fields of its type are set; the others are
 *  zero/NULL. Free it with sylva_msg_free(). */
typedef struct sylva_msg {
  sylva_msg_type type;
  /** The client's "id" re-encoded as compact JSON (a string or a number), NULL if
   *  absent; echo it as "ref". */
  char *ref;
  /** subscribe, unsubscribe, control, edit, fork, get, light: the run id (>= 1). */
  int64_t run;
  /** subscribe: whether "since" was given, and the seq (>= 0). */
  bool has_since;
  int64_t since;
  /** subscribe: the detail asked for (default SYLVA_DETAIL_NODES). */
  sylva_detail detail;
  /** hello: the token, NULL if absent. */
  char *token;
  /** create (optional, else NULL), fork (required): the run name, 1 to
   *  SYLVA_MSG_NAME_MAX bytes of UTF-8 without control characters. */
  char *name;
  /** create: start the run at once (default false). */
  bool start;
  /** create: the parsed and validated scenario. */
  sylva_scenario *scenario;
  /** control: the action, and for step the count (1..SYLVA_MSG_MAX_STEP, default 1). */
  sylva_control_action action;
  int count;
  /** fork, get: the stored iteration (>= 0). */
  int iteration;
  /** light: the height, metres (finite). */
  double z;
  /** edit: plants to add, shaped like scenario plants; species is -1 and the
   *  species' name (a label, resolved by the daemon against the run's world) is
   *  add_plant_species[i]. */
  sylva_scenario_plant *add_plants;
  char **add_plant_species;
  int add_plant_count;
  /** edit: obstacles to add (kind "box" or "zone", max > min on every axis). */
  sylva_scenario_obstacle *add_obstacles;
  int add_obstacle_count;
  /** edit: ids of obstacles to remove (labels). */
  char **remove_obstacles;
  int remove_obstacle_count;
  /** edit: prune now (prune set): the zone prune_zone (a label), or when that is
   *  empty the box [prune_min, prune_max] (max >= min). */
  bool prune;
  char prune_zone[SYLVA_LABEL_MAX];
  double prune_min[3], prune_max[3];
} sylva_msg;

/** Parses one client message: the strict JSON check (RFC 8259, no "\u0000", nesting
 *  at most SYLVA_MSG_MAX_DEPTH), then a top-level object with a known string
 *  "type", an optional "id" (string or number), only the keys of that type, and
 *  every field's type and range. Returns 0, SYLVA_EINVAL (bad message) or
 *  SYLVA_ENOMEM. On failure err (if given) says what and where, starting with the
 *  JSON pointer of the offending value or "(syntax)": "/run: expected an integer
 *  >= 1, got 0", "/type: unknown message type \"foo\" (known: ...)",
 *  "/scenario/plants/0/roots/0: expected [x, y, z]", "(syntax) line 1, column 7
 *  (byte 6): ...". *out is always initialised; after a failure only out->ref may
 *  be set (when the id could be read), so that the error can echo it. Call
 *  sylva_msg_free() in both cases. */
int sylva_msg_parse(const char *text, size_t len, sylva_msg *out, char *err, size_t errlen);

/** Frees what a message holds and zeroes it (a zeroed message is fine). */
void sylva_msg_free(sylva_msg *m);

/** The wire name of a message type ("hello", ...), or NULL for an unknown value. */
const char *sylva_msg_type_name(sylva_msg_type type);

/** What a daemon wants a token for. */
typedef enum sylva_auth {
  SYLVA_AUTH_NONE,    /**< no token */
  SYLVA_AUTH_CHANGES, /**< changing messages only (reading is public) */
  SYLVA_AUTH_ALL,     /**< every message but hello */
} sylva_auth;

/** {"type":"welcome","protocol":1,"server":{"name":"sylva","version":".."},
 *  "auth":true,"public_read":false,"ref":..}: auth says whether the daemon has a
 *  token, public_read whether reading needs none; ref (a JSON value as the client
 *  sent it, or NULL for the greeting on connect) is echoed in reply to a hello. */
char *sylva_msg_welcome(const char *server_version, sylva_auth auth, const char *ref);

/** {"type":"error","code":"...","message":"...","ref":...}. code is one of
 *  bad_request, unknown_run, unauthorized, too_large, busy, internal; message
 *  says what is wrong and where (invalid UTF-8 in it prints as U+FFFD). */
char *sylva_msg_error(const char *code, const char *message, const char *ref);

/** {"type":"created","run":3,"name":"...","ref":...} */
char *sylva_msg_created(int64_t run, const char *name, const char *ref);

/** {"type":"status","run":3,"status":"running","iteration":7,"start_year":2027,
 *  "ref":...}; the status by its name (sylva/run_status.h); start_year only when
 *  not 0 (a run whose scenario gives one). */
char *sylva_msg_status(int64_t run, sylva_run_status status, int iteration, int start_year,
                       const char *ref);

/** One run of a "runs" list. */
typedef struct sylva_run_summary {
  int64_t run;
  const char *name;
  sylva_run_status status;
  int iteration;
  int stems;
  int64_t nodes;
  bool loading; /**< still being restored from the store ("loading": true) */
  const char *sweep; /**< the sweep the run is part of, or NULL (then no sweep fields) */
  int position;      /**< its position in the sweep's product of axes */
  const char *axes;  /**< its place on the sweep's axes: a JSON object of strings (the
                          store's text), or NULL; written member by member, so that a
                          text that is not such an object gives no "axes" */
} sylva_run_summary;

/** {"type":"runs","runs":[{"run":1,"name":"..","status":"running","iteration":4,
 *  "stems":5,"nodes":1234,"sweep":"..","position":0,"axes":{"seed":"1"}}],"ref":...};
 *  the sweep fields only for a swept run. */
char *sylva_msg_runs(const sylva_run_summary *runs, size_t n, const char *ref);

/** Just the array of sylva_msg_runs() ([{"run":1,...}]), for GET /api/runs. */
char *sylva_runs_json(const sylva_run_summary *runs, size_t n);

/** {"type":"snapshot","run":..,"seq":..,"iteration":..,"voxel":..,"world":{"min":[..],
 *  "max":[..]},"obstacles":[..],"plants":[..],"stats":[..],"species":[..],"sky":..,
 *  "start_year":..,"foliage":[..],"plant_species":[..],"leaves":[[id,n],..],"ref":..}:
 *  world, obstacles and plants byte for byte as in sylva_encode_skeleton(); stats per
 *  global stem as in the stats line (compact), the stems' current measures; species:
 *  the labels of the world's species in id order (what an edit's add_plants may name);
 *  start_year (the run's, 0: none) only when given; foliage: per species in id order
 *  {"species","leaf_size","leaf_density","leaf_colour":"#rrggbb"}; plant_species: each
 *  plant's species (its index in species and foliage), in the order of plants; leaves:
 *  every node with sylva_node_info.leaves n > 0, in id order. */
char *sylva_msg_snapshot(int64_t run, int64_t seq, const sylva_world *w, int start_year,
                         const char *ref);

/** The snapshot of a subscriber at `detail`: sylva_msg_snapshot() for
 *  SYLVA_DETAIL_NODES; for SYLVA_DETAIL_STEMS the same message with "detail":"stems"
 *  after "iteration", each stem of "plants" without its "nodes" ({"root":[x,y,z]}), and
 *  no "leaves" (they name nodes). */
char *sylva_msg_snapshot_detail(int64_t run, int64_t seq, const sylva_world *w, int start_year,
                                sylva_detail detail, const char *ref);

/** {"type":"delta","run":..,"seq":..,"iteration":..,"added":[[id,parent,plant,stem,x,
 *  y,z,radius],..],"radii":[[id,radius],..],"shed":[id,..],"leaves":[[id,n],..],
 *  "stats":[..]} of the step that gave journal j (plant: the plant's index as in
 *  "plants" of the snapshot; stem: the stem's index within the plant; leaves: j's
 *  leaf changes, n = 0 for a node that lost its leaves). A client that applies a
 *  snapshot and then each delta (adds the nodes with birth = "iteration", sets the
 *  radii, removes every shed node with its whole subtree, then sets the leaves) holds
 *  the skeleton and the leaves of that iteration. start_year (0: none) dates the
 *  stats' zone entries in calendar years. */
char *sylva_msg_delta(int64_t run, int64_t seq, const sylva_world *w, const sylva_journal *j,
                      int start_year);

/** The delta of a subscriber at `detail`: sylva_msg_delta() for SYLVA_DETAIL_NODES; for
 *  SYLVA_DETAIL_STEMS {"type":"delta","run":..,"seq":..,"iteration":..,"detail":"stems",
 *  "stats":[..],"canopy_cover":..,"stand":..}, the stats and what follows them byte for
 *  byte as in sylva_msg_delta(). */
char *sylva_msg_delta_detail(int64_t run, int64_t seq, const sylva_world *w,
                             const sylva_journal *j, int start_year, sylva_detail detail);

/** {"type":"light_slice","run":..,"iteration":..,"z":..,"origin":[x,y],"voxel":..,
 *  "nx":..,"ny":..,"values":"<base64>","ref":..}: the light of the horizontal voxel
 *  layer holding z (z clamped into the world; "z" reports the layer's centre),
 *  sampled with sylva_world_light_at() at voxel centres. values: nx*ny bytes,
 *  round(light * 255), x fastest; cell (i, j) spans origin + [i, i+1) * voxel in x
 *  and origin + [j, j+1) * voxel in y. Its size is about 1.34 * nx * ny bytes; a
 *  caller that caps its messages checks sylva_world_dims() first. */
char *sylva_msg_light_slice(int64_t run, const sylva_world *w, double z, const char *ref);

/** {"type":"scenarios","scenarios":[{"name":"..","title":".."}],"ref":..}; titles
 *  (or one of them) may be NULL: the title is then the name. */
char *sylva_msg_scenarios(const char *const *names, const char *const *titles, size_t n,
                          const char *ref);

#endif
