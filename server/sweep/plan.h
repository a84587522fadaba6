/* sylva server: sweep plans (`sylva.sweep/1`, docs/cli.md "sweep"): a base scenario
 * and the axes to vary (species, seeds, variants). Their product is the set of runs;
 * a run's position in it is a mixed-radix number over the axes in the plan's order,
 * the last axis varying fastest.
 *
 *   sweep_plan *p; char err[1024];
 *   if (sweep_plan_load("plan.json", &p, err, sizeof err)) ... err names the JSON
 *       pointer: "plan.json: /axes/species/tree: the scenario has no species \"tree\""
 *   for (int i = 0; i < p->runs; i++) { sweep_run r; sweep_plan_run(p, i, &r, ...); }
 *   sweep_plan_free(p); */
#ifndef SYLVA_SERVER_SWEEP_PLAN_H
#define SYLVA_SERVER_SWEEP_PLAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "shade.h"

/** The format string a plan must carry. */
#define SWEEP_FORMAT "sylva.sweep/1"
/** Most runs of a plan without --force. */
#define SWEEP_MAX_RUNS 10000
/** Most runs of a plan with it. */
#define SWEEP_HARD_MAX_RUNS 1000000
/** Most axes (species keys count one each). */
#define SWEEP_MAX_AXES 32

/** The kinds of axis. */
typedef enum sweep_axis_kind { SWEEP_SPECIES, SWEEP_SEED, SWEEP_VARIANT } sweep_axis_kind;

/** One axis: its name ("species/KEY", "seed" or "variant") and its values. */
typedef struct sweep_axis {
  sweep_axis_kind kind;
  char *name;
  char *key;       /**< SWEEP_SPECIES: the scenario's species key */
  int count;
  char **labels;   /**< per value, as stored and shown: a preset's name, a species
                        object's "KEY#k" (1-based), a seed's digits, a variant's name */
  char **values;   /**< per value, as stored in the axis table: labels, but a species
                        object's compact JSON */
  cJSON **json;    /**< per value: the species (a preset string or an object), the
                        seed (a number) or the patch (an array); owned by `plan` */
} sweep_axis;

/** A plan, checked: every axis value applies to the scenario. */
typedef struct sweep_plan {
  char *name;
  char *base;        /**< the path measured trees ("from") are read against: the
                          scenario's file, or the plan's for an inline scenario */
  cJSON *scenario;   /**< the base scenario */
  cJSON *plan;       /**< the plan with its scenario inline */
  char *canonical;   /**< compact JSON of `plan`: what a store keeps of the sweep */
  int axis_count;
  sweep_axis axes[SWEEP_MAX_AXES];
  int runs;          /**< the product of the axes' counts */
  bool base_runs;    /**< the base scenario runs as it is; not so a site without plants
                          whose variants plant it */
  bool shade;        /**< the plan names a day for the report's tree shade hours */
  shade_day shade_day; /**< that day (its year 0: each run's is its own) */
} sweep_plan;

/** One run of a plan. Strings malloc'd (sweep_run_free). */
typedef struct sweep_run {
  int position;
  char *name;       /**< "PLAN: street-tree=utdb:NoEast:PLAC, seed=1, variant=as built" */
  char *scenario;   /**< the run's scenario JSON */
  int value[SWEEP_MAX_AXES]; /**< per axis, the index of its value */
} sweep_run;

/** Reads the "shade" member of a plan object (docs/cli.md, "sweep"): {"date": "MM-DD",
 *  "from": "HH:MM", "to": "HH:MM", "step": MIN}, from and to defaulting to 00:00 and
 *  24:00, step to 10. *present false (and *day untouched) without one. 0, or -1
 *  with err naming the JSON pointer ("/shade/date: no such date 02-30"). */
int sweep_plan_shade(const cJSON *plan, bool *present, shade_day *day, char *err, size_t errlen);

/** Parses and checks a plan (text from path; relative paths in it are against path's
 *  folder). force admits up to SWEEP_HARD_MAX_RUNS runs. 0, or -1 with err naming the
 *  JSON pointer of what is wrong. */
int sweep_plan_parse(const char *text, size_t len, const char *path, bool force,
                     sweep_plan **out, char *err, size_t errlen);
/** Reads a plan file and parses it (sweep_plan_parse). */
int sweep_plan_load(const char *path, bool force, sweep_plan **out, char *err, size_t errlen);
/** The run at a position (0 to runs - 1). 0, or -1 with err (a variant's patch that
 *  does not apply with this run's other values, out of memory). */
int sweep_plan_run(const sweep_plan *p, int position, sweep_run *out, char *err, size_t errlen);
void sweep_run_free(sweep_run *r);
void sweep_plan_free(sweep_plan *p);

#endif
