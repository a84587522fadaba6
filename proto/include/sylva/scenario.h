/* sylva: scenario files (`sylva.scenario/1`, spec/scenario.md): parsing, strict
 * validation and building a world.
 *
 *   sylva_scenario *s; char err[512];
 *   if (sylva_scenario_parse(text, len, &s, err, sizeof err) < 0) ... err names the
 *       JSON pointer of the bad value: "/species/oak/lambda: must be in (0, 1), got 1.5"
 *   sylva_world *w;
 *   if (sylva_scenario_build(s, &w, err, sizeof err) < 0) ...
 *   sylva_scenario_free(s); */
#ifndef SYLVA_SCENARIO_H
#define SYLVA_SCENARIO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sylva/params.h"
#include "sylva/sky.h"
#include "sylva/world.h"

/** The format string a scenario must carry. */
#define SYLVA_SCENARIO_FORMAT "sylva.scenario/1"
/** Deepest JSON nesting a scenario may have. */
#define SYLVA_SCENARIO_MAX_DEPTH 64
/** Most roots of one plant. */
#define SYLVA_SCENARIO_MAX_ROOTS 1000
/** Most species of one scenario. */
#define SYLVA_SCENARIO_MAX_SPECIES 1000
/** Most obstacles of one scenario. */
#define SYLVA_SCENARIO_MAX_OBSTACLES 100000
/** Longest scenario name, bytes. */
#define SYLVA_SCENARIO_NAME_MAX 255
/** Largest seed (2^53: every integer up to it is exact in JSON). */
#define SYLVA_SCENARIO_SEED_MAX 9007199254740992.0
/** Most iterations of a run. */
#define SYLVA_SCENARIO_MAX_ITERATIONS 100000
/** Latest `start_year` (the earliest is 1). */
#define SYLVA_SCENARIO_MAX_YEAR 9999

/** A species of the scenario: its name (the key in "species") and parameters. */
typedef struct sylva_scenario_species {
  char name[SYLVA_LABEL_MAX];
  sylva_species_def def; /**< presets, overrides and defaults resolved */
} sylva_scenario_species;

/** A plant: one root is a tree, several a shrub. */
typedef struct sylva_scenario_plant {
  char id[SYLVA_LABEL_MAX];
  int species;        /**< index into sylva_scenario.species */
  double (*roots)[3]; /**< root_count positions */
  int root_count;
  int age;            /**< years at planting, 0 to SYLVA_MAX_AGE (above 0 only
                           for a species with years); default 0 */
  /** "from": a measured tree (docs/scenario.md, "Plants"), standing at roots[0].
   *  from_file is NULL when the plant has none. */
  char *from_file;      /**< as given: a path relative to the scenario's file */
  char from_format[16]; /**< mat, text, csv or skeleton; "" to sniff */
  int from_model;       /**< 1-based; 0: the first */
  int from_age;         /**< the tree's age in years; -1: from the species' growth */
  /** The measured tree's nodes, read by the caller from from_file before
   *  sylva_scenario_build (the server's files_read_measured); owned by the plant. */
  sylva_plant_node *nodes;
  int node_count;
  int measured_age; /**< the age those nodes were given */
} sylva_scenario_plant;

/** The scenario's light (the `light` key): the paper's zenith sky, or a site's. */
typedef struct sylva_scenario_light {
  bool site;         /**< "sky": "site"; false: "zenith" */
  sylva_sky_def sky; /**< when site: latitude, north, season, diffuse, samples */
  /** When site, optional and together: the site's longitude (degrees, east
   *  positive) and its clock's offset from UTC (hours), for clock times (sylva
   *  shade); clock false without them (times are local solar time). */
  bool clock;
  double longitude, utc_offset;
} sylva_scenario_light;

/** Defaults of a site's sky. */
#define SYLVA_SITE_DIFFUSE 0.5
#define SYLVA_SITE_SAMPLES 64

/** An obstacle: kind "box" or "prism" (solid) or "zone" (a clearance zone, a box or
 *  a prism). A prism's footprint is owned (sylva_scenario_obstacle_clear()): its
 *  points, the outline's ("polygon") then each hole's, and the rings' sizes;
 *  ring_count 0 for a box. A prism's min and max hold its footprint's bounds and
 *  its z range ("z"). */
typedef struct sylva_scenario_obstacle {
  char id[SYLVA_LABEL_MAX];
  double min[3], max[3];
  sylva_obstacle_kind kind;
  double (*points)[2];
  int *ring_sizes;
  int point_count, ring_count;
} sylva_scenario_obstacle;

/** The world's def of an obstacle, pointing into o. */
sylva_obstacle_def sylva_scenario_obstacle_def(const sylva_scenario_obstacle *o);
/** Frees what o owns (its footprint) and leaves it a box. */
void sylva_scenario_obstacle_clear(sylva_scenario_obstacle *o);
/** The JSON object of an obstacle as scenarios, snapshots and the command log write it
 *  (docs/scenario.md, "Obstacles"): {"id", "kind": "box", "min", "max"} for a box,
 *  {"id", "kind": "prism", "polygon", ["holes",] "z"} for a prism, "kind": "zone"
 *  with either shape. Numbers in their shortest exact form; compact without spaces,
 *  else with ", " and ": " as scenario files have them. NULL when out of memory;
 *  free() it. */
char *sylva_obstacle_json(const sylva_obstacle_def *o, bool compact);
/** Reads one obstacle object (a cJSON tree), as a scenario's obstacles are read, into
 *  *out (zeroed first; its footprint owned on success, nothing on failure). On bad
 *  input SYLVA_EINVAL, err naming "<at>/key: message" (at, the object's JSON pointer
 *  in the caller's document, may be ""); SYLVA_ENOMEM. */
struct cJSON;
int sylva_obstacle_read(const struct cJSON *obj, const char *at, sylva_scenario_obstacle *out,
                        char *err, size_t errlen);

/** Most entries of `management`. */
#define SYLVA_SCENARIO_MAX_MANAGEMENT 1000

/** A management action: pruning a zone on a schedule (docs/scenario.md). */
typedef struct sylva_scenario_prune {
  int zone;  /**< index into obstacles, a zone */
  int every; /**< iterations between prunes; 0: once */
  int from;  /**< the first iteration pruned */
} sylva_scenario_prune;

/** A parsed and validated scenario; free it with sylva_scenario_free(). Treat it
 *  as read-only, except that seed and iterations may be overridden (command-line
 *  options) before sylva_scenario_build(). */
typedef struct sylva_scenario {
  char *name;     /**< "untitled" when absent */
  uint64_t seed;  /**< default 1 */
  int iterations; /**< the iteration limit; default 40 */
  int start_year; /**< the calendar year of iteration 0, 1 to SYLVA_SCENARIO_MAX_YEAR;
                       0 when not given */
  double stand_area; /**< m^2 the stand's figures are per (docs/model.md, "Stands"); 0:
                          the roots' widened hull */
  double world_min[3], world_max[3];
  double voxel;   /**< given, or rho/2 of the smallest rho in use */
  sylva_scenario_species *species;
  int species_count;
  sylva_scenario_plant *plants;
  int plant_count;
  int stem_count; /**< roots of all plants */
  sylva_scenario_obstacle *obstacles;
  int obstacle_count;
  sylva_scenario_prune *management;
  int management_count;
  sylva_scenario_light light;
  /** Where the world stands on Earth (the `site` key, as `sylva site` writes it): a
   *  CRS that PROJ understands ("EPSG:32618", "" when not given) and the
   *  coordinates in it of the world's (0, 0): x east and y north in metres from
   *  there. The core never reads it; exports to GIS do. */
  char site_crs[256];
  double site_origin[2];
} sylva_scenario;

/** Parses and validates a scenario: the strict JSON check, then every rule of
 *  scenario.md (known keys only, types, finite numbers, ranges, references, a
 *  world that fits in memory). On success *out is the new scenario and 0 is
 *  returned. On failure *out is NULL, the status is negative (SYLVA_EINVAL for
 *  bad input, SYLVA_ETOOBIG for a world with too many voxels, SYLVA_ENOMEM) and
 *  err holds a message that starts with the JSON pointer of the offending value
 *  ("/plants/0/species: unknown species \"pine\""; "(root)" for the document
 *  itself, as the empty pointer would not be readable) or with "(syntax)" for a JSON
 *  syntax error ("(syntax) line 3, column 14 (byte 52): leading zero in number"). */
int sylva_scenario_parse(const char *text, size_t len, sylva_scenario **out, char *err,
                         size_t errlen);

/** Flags of sylva_scenario_parse_ex(). */
enum {
  /** Refuse a scenario without plants: "plants" missing ("/plants: required") or
   *  empty ("/plants: nothing to grow (the list is empty)"). For a scenario grown as
   *  it is (`sylva run`, `sylva validate`); without it a scenario without plants is
   *  an empty site, to be planted by edits (the daemon's create). */
  SYLVA_SCENARIO_NEED_PLANTS = 1
};

/** sylva_scenario_parse() with SYLVA_SCENARIO_* flags. */
int sylva_scenario_parse_ex(const char *text, size_t len, unsigned flags, sylva_scenario **out,
                            char *err, size_t errlen);

/** A canonical JSON form of s: every species fully resolved (no presets), the
 *  voxel explicit, numbers that read back exactly; parsing it gives the same
 *  scenario. malloc'd, ends with a newline; NULL when out of memory. */
char *sylva_scenario_json(const sylva_scenario *s);

/** Creates the world of s: species, obstacles, then plants (so that a root inside
 *  an obstacle is found). On failure nothing is left behind, *out is NULL, and err
 *  names the culprit ("/plants/1/roots/0: root inside an obstacle"). */
int sylva_scenario_build(const sylva_scenario *s, sylva_world **out, char *err, size_t errlen);

/** Frees a scenario (NULL is fine). */
void sylva_scenario_free(sylva_scenario *s);

/** A species as the canonical JSON object of a scenario's species (every key, no
 *  preset), NUL-terminated and malloc'd; NULL when out of memory. */
char *sylva_species_json(const sylva_species_def *def);

/** Number of species presets. */
int sylva_preset_count(void);
/** Name of preset i (0 <= i < count), or NULL. */
const char *sylva_preset_name(int i);
/** Looks a preset up by name; 0 and *out filled, or SYLVA_ENOTFOUND. */
int sylva_preset_find(const char *name, sylva_species_def *out);

#endif
