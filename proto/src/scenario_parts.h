/* Private to libsylva-proto: the pieces of the scenario parser (scenario.c) that
 * the protocol parser (protocol.c) reuses: JSON-pointer error reporting, typed
 * readers of cJSON values, plants, obstacles and whole scenarios read from a
 * cJSON tree. Every reader names the JSON pointer of the offending value in its
 * message and returns 0 or a negative sylva_status. */
#ifndef SYLVA_PROTO_SCENARIO_PARTS_H
#define SYLVA_PROTO_SCENARIO_PARTS_H

#include <cjson/cJSON.h>
#include <stdbool.h>
#include <stddef.h>

#include "sylva/encode.h"
#include "sylva/scenario.h"

#if defined(__GNUC__)
#define SYLVA__PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define SYLVA__PRINTF_LIKE(f, a)
#endif

/** Parser state: the JSON pointer (RFC 6901) of the value being read and where
 *  messages go. */
typedef struct sylva__parser {
  char ptr[1024]; /**< pointer of the value being checked; "" is the root */
  size_t plen;    /**< length of ptr */
  size_t base;    /**< length of the prefix where the scenario document starts (0 for a
                       scenario file, 9 for "/scenario" inside a protocol message) */
  char *err;      /**< message buffer (may be NULL) */
  size_t errlen;
} sylva__parser;

/** Appends one reference token (escaped as RFC 6901 wants); returns the length to
 *  restore with sylva__ptr_pop(). The pointer is truncated, never overflows. */
size_t sylva__ptr_push(sylva__parser *p, const char *token);
/** Appends an array index. */
size_t sylva__ptr_push_index(sylva__parser *p, size_t i);
/** Restores the pointer to an earlier length. */
void sylva__ptr_pop(sylva__parser *p, size_t old);

/** Writes "<pointer>: <message>" ("(root)" for the empty pointer); returns
 *  SYLVA_EINVAL. */
int sylva__fail(sylva__parser *p, const char *fmt, ...) SYLVA__PRINTF_LIKE(2, 3);
/** sylva__fail() at the member key of the current value (present or not). */
int sylva__fail_at_key(sylva__parser *p, const char *key, const char *fmt, ...)
    SYLVA__PRINTF_LIKE(3, 4);
/** Writes "out of memory"; returns SYLVA_ENOMEM. */
int sylva__fail_nomem(sylva__parser *p);

/** A user string for a message: quoted, at most about 60 bytes, control bytes as '?'. */
const char *sylva__quote(char buf[80], const char *s);
/** "an object", "a string", ... for messages. */
const char *sylva__type_name(const cJSON *item);
/** Shortest exact text of a number, for messages. */
const char *sylva__num(char buf[SYLVA_FMT_BUFSIZE], double v);

/** Every member of obj must be one of known[] and appear once; an unknown key is
 *  named (with a suggestion when it looks like a typo). */
int sylva__check_keys(sylva__parser *p, const cJSON *obj, const char *const *known, size_t count);
/** A species object (as a scenario's species) into *out, with the defaults for what
 *  it leaves out; SYLVA_EINVAL when it is not a valid species. */
int sylva__species_from_json(const cJSON *obj, sylva_species_def *out);

/** The value must be an object. */
int sylva__want_object(sylva__parser *p, const cJSON *item);
/** A finite number. */
int sylva__want_number(sylva__parser *p, const cJSON *item, double *out);
/** A string; *out points into the cJSON tree. */
int sylva__want_string(sylva__parser *p, const cJSON *item, const char **out);
/** A label: a string of 1 to SYLVA_LABEL_MAX - 1 bytes, copied to out. */
int sylva__want_label(sylva__parser *p, const cJSON *item, char out[SYLVA_LABEL_MAX]);
/** An integral number in [lo, hi]. */
int sylva__want_integer(sylva__parser *p, const cJSON *item, double lo, double hi, double *out);
/** [x, y, z] of finite numbers. */
int sylva__want_vec3(sylva__parser *p, const cJSON *item, double out[3]);
/** The integral member `key` of obj, in [lo, hi], into *out. *present tells whether
 *  it was there (*out then keeps its value); with present NULL it is required. */
int sylva__read_integer(sylva__parser *p, const cJSON *obj, const char *key, double lo,
                        double hi, bool *present, double *out);

/** The `light` member (scenario_light.c). */
int sylva__parse_light(sylva__parser *p, const cJSON *item, sylva_scenario_light *out);
/** Its canonical JSON, for a site's sky. */
struct sylva__strbuf;
void sylva__put_light(struct sylva__strbuf *b, const sylva_scenario_light *l);

/** An id and its index, for duplicate detection and lookups. */
typedef struct sylva__id_ref {
  const char *id;
  int index;
} sylva__id_ref;

/** Finds the first repeated id (refs is sorted in place): *first and *second are the
 *  indices of its first occurrence and of the earliest repetition; false if every
 *  id is unique. */
bool sylva__find_duplicate(sylva__id_ref *refs, int count, int *first, int *second);

/** A plant object {"id", "species", "roots"} into pl (pl->roots malloc'd; free it
 *  even on failure). by_name: the species_count species sorted by name, to resolve
 *  the species to an index; with by_name NULL the species stays unresolved
 *  (pl->species = -1), must be a label, and *species_name (if given) points to it
 *  in the cJSON tree. *stem_count grows by the plant's roots; the world's limit
 *  of SYLVA_MAX_STEMS is checked against it. */
int sylva__parse_plant(sylva__parser *p, const cJSON *obj, const sylva__id_ref *by_name,
                       int species_count, int *stem_count, sylva_scenario_plant *pl,
                       const char **species_name);
/** An obstacle object (obstacle.c): {"id", "kind": "box", "min", "max"} with max > min,
 *  {"id", "kind": "prism", "polygon", "holes", "z"}, or "kind": "zone" with either
 *  shape. On failure o may own a partial footprint (sylva_scenario_obstacle_clear()). */
int sylva__parse_obstacle(sylva__parser *p, const cJSON *obj, sylva_scenario_obstacle *o);
/** Parses `management` (after the obstacles, which it names) into s. */
int sylva__parse_management(sylva__parser *p, const cJSON *item, sylva_scenario *s);
/** Writes s's management list in canonical form. */
void sylva__put_management(struct sylva__strbuf *b, const sylva_scenario *s);
/** Gives world w (built from s, obstacles in order) s's pruning schedules. */
int sylva__build_management(sylva__parser *p, const sylva_scenario *s, sylva_world *w);

/** A whole scenario from a cJSON tree, errors under the parser's current pointer
 *  (set p->base to its length); flags as for sylva_scenario_parse_ex(). On failure
 *  *out is NULL; the status is negative (SYLVA_EINVAL, SYLVA_ETOOBIG for a world with
 *  too many voxels, SYLVA_ENOMEM). */
int sylva__scenario_from_json(sylva__parser *p, const cJSON *root, unsigned flags,
                              sylva_scenario **out);

#endif
