/* The report's data: the runs of a sweep (or of a store without sweeps), their stats
 * rows at the reported years and at their last iteration, every row's height and
 * crown diameter for the plots, and the summary (report.h). */
#include "report.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <cjson/cJSON.h>

#include "plan.h"
#include "shade.h"
#include "sweep_store.h"
#include "sylva/scenario.h"
#include "utdb.h"

/* ---- small helpers --------------------------------------------------------------- */

static int nomem(char *err, size_t errlen) {
  return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
}

/* Makes room for `need` elements of `size` bytes in *p (capacity *cap). */
static bool grow(void **p, size_t *cap, size_t need, size_t size) {
  if (need <= *cap) return true;
  size_t n = *cap ? *cap : 8;
  while (n < need) n *= 2;
  void *q = realloc(*p, n * size);
  if (!q) return false;
  *p = q;
  *cap = n;
  return true;
}

/* The index of name in list[0..*n), appended when missing; -1 when out of memory. */
static int intern(char ***list, int *n, const char *name) {
  for (int i = 0; i < *n; i++)
    if (strcmp((*list)[i], name) == 0) return i;
  char *copy = strdup(name);
  char **l = copy ? realloc(*list, (size_t)(*n + 1) * sizeof *l) : NULL;
  if (!l) {
    free(copy);
    return -1;
  }
  *list = l;
  l[*n] = copy;
  return (*n)++;
}

static void free_names(char **list, int n) {
  for (int i = 0; i < n; i++) free(list[i]);
  free(list);
}

static int compare_doubles(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* ---- formats and years ---------------------------------------------------------- */

bool report_format_from_path(const char *path, report_format *out) {
  const char *dot = path ? strrchr(path, '.') : NULL;
  if (!dot || strchr(dot, '/')) return false;
  if (strcasecmp(dot, ".csv") == 0) *out = REPORT_CSV;
  else if (strcasecmp(dot, ".html") == 0 || strcasecmp(dot, ".htm") == 0) *out = REPORT_HTML;
  else if (strcasecmp(dot, ".pdf") == 0) *out = REPORT_PDF;
  else return false;
  /* a bare ".csv" names no file */
  return dot != path && dot[-1] != '/';
}

static int compare_ints(const void *a, const void *b) {
  int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

bool report_parse_years(const char *text, int years[REPORT_MAX_YEARS], int *count, char *err,
                        size_t errlen) {
  *count = 0;
  if (!text || !text[0]) {
    server_fail(err, errlen, 0, "expected years like 10,20,40, got an empty list");
    return false;
  }
  const char *p = text;
  for (;;) {
    const char *end = strchr(p, ',');
    size_t len = end ? (size_t)(end - p) : strlen(p);
    if (len == 0) {
      server_fail(err, errlen, 0, "an empty year in '%s'", text);
      return false;
    }
    /* digits only: a sign, a space or a fraction is not a year */
    for (size_t i = 0; i < len; i++)
      if (!isdigit((unsigned char)p[i])) {
        server_fail(err, errlen, 0, "'%.*s' is not a whole number of years from 1 to %d", (int)len, p,
             REPORT_MAX_YEAR);
        return false;
      }
    long v = 0;
    for (size_t i = 0; i < len && v <= REPORT_MAX_YEAR; i++) v = v * 10 + (p[i] - '0');
    if (v < 1 || v > REPORT_MAX_YEAR) {
      server_fail(err, errlen, 0, "year '%.*s' is not from 1 to %d", (int)len, p, REPORT_MAX_YEAR);
      return false;
    }
    bool dup = false;
    for (int i = 0; i < *count; i++) dup |= years[i] == (int)v;
    if (!dup) {
      if (*count == REPORT_MAX_YEARS) {
        server_fail(err, errlen, 0, "more than %d years", REPORT_MAX_YEARS);
        return false;
      }
      years[(*count)++] = (int)v;
    }
    if (!end) break;
    p = end + 1;
  }
  qsort(years, (size_t)*count, sizeof *years, compare_ints);
  return true;
}

/* ---- number formats ------------------------------------------------------------- */

void report_format_number(char *buf, size_t size, double v) {
  if (!buf || !size) return;
  if (isnan(v)) {
    buf[0] = '\0';
    return;
  }
  for (int prec = 15; prec <= 17; prec++) {
    snprintf(buf, size, "%.*g", prec, v);
    if (strtod(buf, NULL) == v) return;
  }
}

void report_format_stat(char *buf, size_t size, const report_stat *s, int n) {
  if (s->n == 0) {
    snprintf(buf, size, "–");
    return;
  }
  int len = snprintf(buf, size, "%.3f (%.3f–%.3f)", s->median, s->min, s->max);
  if (s->n < n && len >= 0 && (size_t)len < size)
    snprintf(buf + len, size - (size_t)len, ", %d of %d", s->n, n);
}

void report_format_first(char *buf, size_t size, const report_stat *s, int n) {
  if (s->n == 0) {
    snprintf(buf, size, "never, 0 of %d", n);
    return;
  }
  char med[32], lo[32], hi[32];
  report_format_number(med, sizeof med, s->median);
  report_format_number(lo, sizeof lo, s->min);
  report_format_number(hi, sizeof hi, s->max);
  snprintf(buf, size, "%s (%s–%s), %d of %d", med, lo, hi, s->n, n);
}

void report_format_year(char *buf, size_t size, const report *r, int i) {
  if (r->common_start_year)
    snprintf(buf, size, "%d (%d)", r->years[i], r->common_start_year + r->years[i]);
  else
    snprintf(buf, size, "%d", r->years[i]);
}

const char *report_group_axis(const report *r, const report_group *g) {
  return g->axis < 0 ? "all runs" : r->axes[g->axis];
}

/* ---- freeing -------------------------------------------------------------------- */

static void free_rows(report_row *rows, size_t n) {
  for (size_t i = 0; i < n; i++) {
    free(rows[i].first);
    free(rows[i].clearance);
  }
  free(rows);
}

void report_free(report *r) {
  if (!r) return;
  free(r->db);
  free(r->sweep);
  for (int i = 0; i < r->nruns; i++) {
    free(r->runs[i].name);
    if (r->runs[i].values)
      for (int a = 0; a < r->naxes; a++) free(r->runs[i].values[a]);
    free(r->runs[i].values);
    if (r->runs[i].shade)
      for (int y = 0; y < r->nyears; y++) free(r->runs[i].shade[y].obstacles);
    free(r->runs[i].shade);
  }
  free(r->runs);
  free_names(r->shade_obstacles, r->nshade_obstacles);
  free_names(r->axes, r->naxes);
  for (int i = 0; i < r->nspecies; i++) {
    free(r->species[i].label);
    free(r->species[i].utdb);
  }
  free(r->species);
  free_names(r->keys, r->nkeys);
  free_names(r->plants, r->nplants);
  free_names(r->zones, r->nzones);
  free_names(r->obstacles, r->nobstacles);
  free_rows(r->rows, r->nrows);
  free_rows(r->finals, r->nfinals);
  free(r->samples);
  for (size_t i = 0; i < r->ngroups; i++) free(r->groups[i].first);
  free(r->groups);
  free(r);
}

/* ---- the runs to report --------------------------------------------------------- */

/* A swept run as listed: its id, sweep, position and axes (copied). */
typedef struct swept {
  int64_t run;
  char *sweep;
  int position;
  char *axes;
} swept;

typedef struct swept_list {
  swept *v;
  size_t n, cap;
  bool oom;
} swept_list;

static int collect_swept(const store_sweep_run *r, void *ctx) {
  swept_list *l = ctx;
  if (!grow((void **)&l->v, &l->cap, l->n + 1, sizeof *l->v)) goto oom;
  swept *s = &l->v[l->n];
  s->run = r->run;
  s->position = r->position;
  s->sweep = strdup(r->sweep ? r->sweep : "");
  s->axes = strdup(r->axes ? r->axes : "{}");
  if (!s->sweep || !s->axes) {
    free(s->sweep);
    free(s->axes);
    goto oom;
  }
  l->n++;
  return 0;
oom:
  l->oom = true;
  return 1;
}

static void free_swept(swept_list *l) {
  for (size_t i = 0; i < l->n; i++) {
    free(l->v[i].sweep);
    free(l->v[i].axes);
  }
  free(l->v);
}

/* The distinct sweep names of l, ", "-separated, into buf. */
static int sweep_names(const swept_list *l, char *buf, size_t size) {
  int count = 0;
  size_t len = 0;
  buf[0] = '\0';
  for (size_t i = 0; i < l->n; i++) {
    bool seen = false;
    for (size_t j = 0; j < i && !seen; j++) seen = strcmp(l->v[j].sweep, l->v[i].sweep) == 0;
    if (seen) continue;
    count++;
    if (len < size) {
      int w = snprintf(buf + len, size - len, "%s\"%s\"", count > 1 ? ", " : "", l->v[i].sweep);
      if (w > 0) len += (size_t)w;
    }
  }
  return count;
}

/* plan[a][b][c], or NULL where any is missing (or there is no plan). */
static const cJSON *plan_at(const cJSON *plan, const char *a, const char *b, const char *c) {
  return cJSON_GetObjectItemCaseSensitive(
      cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(plan, a), b), c);
}

/* ---- labels of species ---------------------------------------------------------- */

/* What the gathering holds besides the report. */
typedef struct gather {
  report *r;
  cJSON *plan;      /* the sweep's plan, or NULL */
  sylva_utdb *utdb; /* the database, parsed on first need */
  size_t rows_cap, finals_cap, samples_cap;
  void (*warn)(const char *msg); /* the request's */
  int no_site;       /* runs with a shade day but no latitude */
  char *no_site_run; /* the first of them */
  char *err;
  size_t errlen;
} gather;

/* The label of a species key of a run: its value on the run's axis "species/KEY"
 * (a preset's name, or "KEY#k" for the k-th species object of the plan's axis), else
 * the preset the plan's scenario names for it, else the key. *preset tells whether
 * the label is a preset's name used as it is (then the library's curves apply). */
static char *species_label(const gather *g, const cJSON *axes, const char *key, bool *preset) {
  *preset = false;
  char axis[300];
  snprintf(axis, sizeof axis, "species/%s", key);
  const cJSON *v = axes ? cJSON_GetObjectItemCaseSensitive(axes, axis) : NULL;
  if (cJSON_IsString(v) && v->valuestring) {
    const char *value = v->valuestring;
    if (value[0] != '{') {
      *preset = true;
      return strdup(value);
    }
    /* a species object: its place in the plan's axis names it */
    cJSON *obj = cJSON_Parse(value);
    const cJSON *list = plan_at(g->plan, "axes", "species", key);
    int k = 0, found = 0;
    const cJSON *e;
    cJSON_ArrayForEach(e, list) {
      k++;
      if (obj && !found && cJSON_Compare(e, obj, true)) found = k;
    }
    cJSON_Delete(obj);
    char buf[400];
    snprintf(buf, sizeof buf, "%s#%d", key, found ? found : 1);
    return strdup(found ? buf : value);
  }
  const cJSON *sp = plan_at(g->plan, "scenario", "species", key);
  const cJSON *pre = cJSON_GetObjectItemCaseSensitive(sp, "preset");
  /* a preset with overrides is not the preset: it keeps its key */
  if (cJSON_IsString(pre) && pre->valuestring && cJSON_GetArraySize(sp) == 1) {
    *preset = true;
    return strdup(pre->valuestring);
  }
  return strdup(key);
}

/* The index of the species labelled `label`, added (with the database's curves for a
 * library preset) when new; -1 and err on failure. */
static int species_index(gather *g, const char *label, bool preset, int run) {
  report *r = g->r;
  for (int i = 0; i < r->nspecies; i++)
    if (strcmp(r->species[i].label, label) == 0) return i;
  report_species *s = realloc(r->species, (size_t)(r->nspecies + 1) * sizeof *s);
  if (!s) return nomem(g->err, g->errlen), -1;
  r->species = s;
  report_species *n = &s[r->nspecies];
  *n = (report_species){.label = strdup(label), .picture_run = run};
  if (!n->label) return nomem(g->err, g->errlen), -1;
  r->nspecies++;
  if (preset && strncmp(label, "utdb:", 5) == 0) {
    char region[64];
    const char *code = strchr(label + 5, ':');
    if (code && (size_t)(code - (label + 5)) < sizeof region) {
      if (!g->utdb && sylva_utdb_builtin(&g->utdb)) return nomem(g->err, g->errlen), -1;
      memcpy(region, label + 5, (size_t)(code - (label + 5)));
      region[code - (label + 5)] = '\0';
      const sylva_utdb_species *u = sylva_utdb_find(g->utdb, region, code + 1);
      if (u) {
        n->utdb = malloc(sizeof *n->utdb);
        if (!n->utdb) return nomem(g->err, g->errlen), -1;
        /* a species without the four curves simply has none drawn */
        if (sylva_fit_targets_utdb(u, n->utdb, NULL, 0)) {
          free(n->utdb);
          n->utdb = NULL;
        }
      }
    }
  }
  return r->nspecies - 1;
}

/* ---- one run's stats ------------------------------------------------------------ */

/* A plant of the run's scenario. */
typedef struct run_plant {
  int plant, key, species; /* report indices */
} run_plant;

/* What is known of a stem while its rows are read. */
typedef struct stem_slot {
  bool known;
  int plant, key, species;
  int64_t pruned; /* summed so far; -1 while no row reported conflicts */
} stem_slot;

typedef struct run_pass {
  gather *g;
  int run;
  const cJSON *plants;   /* the scenario's plants */
  run_plant *plant_info; /* per entry of plants */
  int nplants;
  stem_slot *slots;
  size_t nslots;
  int status; /* the first failure inside the callback */
  int died_at;  /* the last iteration whose stand's died is in died */
  double died;  /* the stand's died summed over iterations 1 to died_at; NAN once one
                   is not stored */
} run_pass;

/* The (index, value) pairs of a compact JSON object of a stats row: each zone's
 * "first", or each obstacle's clearance. */
static int parse_pairs(run_pass *p, const char *json, bool zones, report_kv **out, int *n) {
  *out = NULL;
  *n = 0;
  if (!json) return SERVER_OK;
  report *r = p->g->r;
  cJSON *o = cJSON_Parse(json);
  if (!o) {
    /* cJSON says nothing of its memory; a stored object that does not parse is
     * damage to report, not to guess at */
    return server_fail(p->g->err, p->g->errlen, SERVER_EFAIL, "%s: run \"%s\": a stats row's %s is "
                "not JSON: %.80s", r->db, r->runs[p->run].name, zones ? "zones" : "clearance",
                json);
  }
  int count = cJSON_GetArraySize(o);
  if (count > 0) {
    *out = malloc((size_t)count * sizeof **out);
    if (!*out) {
      cJSON_Delete(o);
      return nomem(p->g->err, p->g->errlen);
    }
  }
  const cJSON *e;
  cJSON_ArrayForEach(e, o) {
    const cJSON *v = zones ? cJSON_GetObjectItemCaseSensitive(e, "first") : e;
    if (!e->string || !cJSON_IsNumber(v)) continue;
    int idx = zones ? intern(&r->zones, &r->nzones, e->string)
                    : intern(&r->obstacles, &r->nobstacles, e->string);
    if (idx < 0) {
      cJSON_Delete(o);
      return nomem(p->g->err, p->g->errlen);
    }
    (*out)[(*n)++] = (report_kv){idx, v->valuedouble};
  }
  cJSON_Delete(o);
  return SERVER_OK;
}

/* Resolves a stem's plant (by id in the scenario) the first time it is seen. */
static int stem_of(run_pass *p, const store_stats_row *row, stem_slot **out) {
  if (row->stem < 0) return server_fail(p->g->err, p->g->errlen, SERVER_EFAIL, "a negative stem");
  size_t s = (size_t)row->stem;
  if (s >= p->nslots) {
    size_t n = p->nslots ? p->nslots : 8;
    while (n <= s) n *= 2;
    stem_slot *v = realloc(p->slots, n * sizeof *v);
    if (!v) return nomem(p->g->err, p->g->errlen);
    memset(v + p->nslots, 0, (n - p->nslots) * sizeof *v);
    p->slots = v;
    p->nslots = n;
  }
  stem_slot *slot = &p->slots[s];
  if (!slot->known) {
    report *r = p->g->r;
    const char *plant = row->plant ? row->plant : "";
    int i = 0, found = -1;
    const cJSON *e;
    cJSON_ArrayForEach(e, p->plants) {
      const cJSON *id = cJSON_GetObjectItemCaseSensitive(e, "id");
      if (found < 0 && cJSON_IsString(id) && strcmp(id->valuestring, plant) == 0) found = i;
      i++;
    }
    if (found >= 0) {
      slot->plant = p->plant_info[found].plant;
      slot->key = p->plant_info[found].key;
      slot->species = p->plant_info[found].species;
    } else {
      /* a plant an edit added: its species label is not in the scenario; it is
       * reported under its plant id's species key if known, else as "edited" */
      slot->plant = intern(&r->plants, &r->nplants, plant);
      slot->key = intern(&r->keys, &r->nkeys, "(edit)");
      slot->species = species_index(p->g, "(added by an edit)", false, p->run);
      if (slot->plant < 0 || slot->key < 0) return nomem(p->g->err, p->g->errlen);
      if (slot->species < 0) return SERVER_ENOMEM;
    }
    slot->pruned = -1;
    slot->known = true;
  }
  *out = slot;
  return SERVER_OK;
}

/* Appends a row (reported or final) for a stats row. */
static int add_row(run_pass *p, const store_stats_row *row, const stem_slot *slot, int year,
                   report_row **rows, size_t *n, size_t *cap) {
  if (!grow((void **)rows, cap, *n + 1, sizeof **rows)) return nomem(p->g->err, p->g->errlen);
  report_row *o = &(*rows)[*n];
  *o = (report_row){
      .run = p->run, .species = slot->species, .key = slot->key, .plant = slot->plant,
      .stem = row->plant_stem, .year = year, .iteration = row->iteration, .age = row->age,
      .height = row->height, .dbh = row->dbh, .crown_diameter = row->crown_width,
      .crown_height = row->crown_height, .leaf_area = row->leaf_area, .co2 = row->co2,
      .co2_sequestered = row->co2_sequestered, .canopy_cover = row->canopy_cover,
      .shade_ground = NAN, .pruned = slot->pruned};
  const double stand[REPORT_STAND_FIGURES] = {
      [REPORT_STEMS_PER_HA] = row->stand.stems_per_ha, [REPORT_BASAL_AREA] = row->stand.basal_area,
      [REPORT_QMD] = row->stand.qmd, [REPORT_DOMINANT_HEIGHT] = row->stand.dominant_height,
      [REPORT_SDI] = row->stand.sdi, [REPORT_CV_DBH] = row->stand.cv_dbh, [REPORT_DIED] = p->died};
  memcpy(o->stand, stand, sizeof stand);
  (*n)++;
  int rc = parse_pairs(p, row->zones, true, &o->first, &o->nfirst);
  if (!rc) rc = parse_pairs(p, row->clearance, false, &o->clearance, &o->nclearance);
  return rc;
}

static int on_stats(const store_stats_row *row, void *ctx) {
  run_pass *p = ctx;
  gather *g = p->g;
  report *r = g->r;
  stem_slot *slot = NULL;
  int rc = stem_of(p, row, &slot);
  if (rc) goto failed;
  if (row->pruned >= 0) {
    slot->pruned = (slot->pruned < 0 ? 0 : slot->pruned) + row->pruned;
    r->conflicts = true;
  }
  if (row->iteration != p->died_at) { /* the stand's, once per iteration */
    p->died_at = row->iteration;
    p->died = row->stand.died < 0 ? NAN : p->died + row->stand.died;
  }
  if (!grow((void **)&r->samples, &g->samples_cap, r->nsamples + 1, sizeof *r->samples)) {
    rc = nomem(g->err, g->errlen);
    goto failed;
  }
  r->samples[r->nsamples++] =
      (report_sample){slot->species, row->iteration, row->height, row->crown_width};
  for (int i = 0; i < r->nyears; i++)
    if (r->years[i] == row->iteration) {
      rc = add_row(p, row, slot, i, &r->rows, &r->nrows, &g->rows_cap);
      if (rc) goto failed;
    }
  if (row->iteration == r->runs[p->run].last_iteration) {
    rc = add_row(p, row, slot, -1, &r->finals, &r->nfinals, &g->finals_cap);
    if (rc) goto failed;
  }
  if (row->plant_stem > 0) r->multi_stem = true;
  return 0;
failed:
  p->status = rc;
  return 1;
}

/* ---- one run's tree shade ------------------------------------------------------- */

/* The tree shade of world w (run idx at reported year y) on the ground and on each
 * solid obstacle of cols[0..ncols) (indices into r->shade_obstacles). */
static int shade_at(gather *g, const sylva_world *w, const shade_site *site, int idx, int y,
                    const int *cols, int ncols) {
  report *r = g->r;
  report_run *run = &r->runs[idx];
  shade_day day = r->shade_day;
  day.year = run->start_year > 0 ? run->start_year + r->years[y] : shade_default_day().year;
  shade_result res;
  char why[512];
  int rc = shade_compute_threads(w, site, &day, NULL, 0, &res, why, sizeof why);
  if (rc) {
    shade_result_free(&res);
    return server_fail(g->err, g->errlen, rc, "%s: run \"%s\": the shade of iteration %d: %s",
                       r->db, run->name, r->years[y], why);
  }
  report_shade *out = &run->shade[y];
  for (int s = 0; s < res.surface_count; s++)
    if (res.surfaces[s].obstacle < 0 && res.surfaces[s].count)
      out->ground = res.surfaces[s].mean_added;
  if (ncols && !(out->obstacles = malloc((size_t)ncols * sizeof *out->obstacles))) {
    shade_result_free(&res);
    return nomem(g->err, g->errlen);
  }
  for (int c = 0; c < ncols; c++) {
    int id = sylva_world_find_obstacle(w, r->shade_obstacles[cols[c]]);
    shade_surface sum;
    if (id < 0) continue;
    shade_obstacle_summary(&res, id, &sum);
    /* a box wholly outside the world has no cells: no value, not 0 */
    if (sum.count) out->obstacles[out->nobstacles++] = (report_kv){cols[c], sum.mean_added};
  }
  shade_result_free(&res);
  return SERVER_OK;
}

/* Run idx's tree shade at every reported year it reached, once each; its rows from
 * first_row on get their ground value. */
static int run_shade(gather *g, store *st, const store_run *sr, const cJSON *scen, int idx,
                     size_t first_row) {
  report *r = g->r;
  report_run *run = &r->runs[idx];
  if (!(run->shade = calloc((size_t)r->nyears, sizeof *run->shade))) return nomem(g->err, g->errlen);
  for (int y = 0; y < r->nyears; y++) run->shade[y].ground = NAN;
  /* the scenario's solid obstacles are columns even where the sun cannot be had */
  int ncols = 0, *cols = malloc(((size_t)cJSON_GetArraySize(
                                      cJSON_GetObjectItemCaseSensitive(scen, "obstacles")) + 1) *
                                  sizeof *cols);
  if (!cols) return nomem(g->err, g->errlen);
  const cJSON *e;
  cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(scen, "obstacles")) {
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(e, "id");
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(e, "kind");
    if (!cJSON_IsString(id) || (cJSON_IsString(kind) && strcmp(kind->valuestring, "zone") == 0))
      continue;
    int k = intern(&r->shade_obstacles, &r->nshade_obstacles, id->valuestring);
    if (k < 0) {
      free(cols);
      return nomem(g->err, g->errlen);
    }
    cols[ncols++] = k;
  }
  sylva_scenario *s = NULL;
  char why[512];
  int rc = SERVER_OK;
  shade_site site;
  if (sylva_scenario_parse(sr->scenario, strlen(sr->scenario), &s, why, sizeof why))
    rc = server_fail(g->err, g->errlen, SERVER_EFAIL, "%s: run \"%s\": its stored scenario: %s",
                     r->db, sr->name, why);
  else if (!shade_site_of(s, &site)) {
    if (!g->no_site++ && !(g->no_site_run = strdup(sr->name))) rc = nomem(g->err, g->errlen);
  } else {
    for (int y = 0; y < r->nyears && !rc && r->years[y] <= sr->last_iteration; y++) {
      sylva_world *w = NULL;
      if (store_world_at(st, sr->id, r->years[y], g->warn, &w))
        rc = server_fail(g->err, g->errlen, SERVER_EFAIL, "%s: run \"%s\": %s", r->db, sr->name,
                         store_error(st));
      else
        rc = shade_at(g, w, &site, idx, y, cols, ncols);
      if (w) sylva_world_destroy(w);
    }
  }
  sylva_scenario_free(s);
  free(cols);
  for (size_t i = first_row; !rc && i < r->nrows; i++)
    r->rows[i].shade_ground = run->shade[r->rows[i].year].ground;
  return rc;
}

/* Reads one run: its scenario's plants, species and obstacles, then its stats. */
static int gather_run(gather *g, store *st, const store_run *sr, const char *axes_json,
                      int position) {
  report *r = g->r;
  int idx = r->nruns;
  report_run *runs = realloc(r->runs, (size_t)(idx + 1) * sizeof *runs);
  if (!runs) return nomem(g->err, g->errlen);
  r->runs = runs;
  report_run *run = &runs[idx];
  *run = (report_run){.id = sr->id, .name = strdup(sr->name), .position = position,
                      .start_year = sr->start_year, .years = sr->years,
                      .conflicts = sr->reports_conflicts, .stand = sr->stand,
                      .last_iteration = sr->last_iteration};
  r->nruns++;
  if (sr->stand) r->stand = true;
  if (!run->name) return nomem(g->err, g->errlen);
  if (sr->years || sr->start_year) r->calendar = true;
  if (sr->last_iteration > r->max_iteration) r->max_iteration = sr->last_iteration;

  cJSON *axes = axes_json ? cJSON_Parse(axes_json) : NULL;
  if (axes_json && !axes)
    return server_fail(g->err, g->errlen, SERVER_EFAIL, "%s: run \"%s\": its axes are not JSON", r->db,
                sr->name);
  int rc = SERVER_OK;
  if (r->naxes) {
    run->values = calloc((size_t)r->naxes, sizeof *run->values);
    if (!run->values) rc = nomem(g->err, g->errlen);
    for (int a = 0; !rc && a < r->naxes; a++) {
      const cJSON *v = cJSON_GetObjectItemCaseSensitive(axes, r->axes[a]);
      bool preset;
      if (strncmp(r->axes[a], "species/", 8) == 0 && cJSON_IsString(v))
        run->values[a] = species_label(g, axes, r->axes[a] + 8, &preset);
      else
        run->values[a] = strdup(cJSON_IsString(v) && v->valuestring ? v->valuestring : "");
      if (!run->values[a]) rc = nomem(g->err, g->errlen);
    }
  }

  cJSON *scen = rc ? NULL : cJSON_Parse(sr->scenario ? sr->scenario : "");
  if (!rc && !scen)
    rc = server_fail(g->err, g->errlen, SERVER_EFAIL, "%s: run \"%s\": its stored scenario is not JSON",
              r->db, sr->name);
  run_pass p = {.g = g, .run = idx, .plants = cJSON_GetObjectItemCaseSensitive(scen, "plants"),
                .died_at = 0, .died = 0.0};
  p.nplants = cJSON_GetArraySize(p.plants);
  if (!rc && p.nplants) {
    p.plant_info = calloc((size_t)p.nplants, sizeof *p.plant_info);
    if (!p.plant_info) rc = nomem(g->err, g->errlen);
  }
  int i = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, p.plants) {
    if (rc) break;
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(e, "id");
    const cJSON *key = cJSON_GetObjectItemCaseSensitive(e, "species");
    const char *k = cJSON_IsString(key) ? key->valuestring : "";
    bool preset;
    char *label = species_label(g, axes, k, &preset);
    if (!label) {
      rc = nomem(g->err, g->errlen);
      break;
    }
    run_plant *pi = &p.plant_info[i++];
    pi->plant = intern(&r->plants, &r->nplants, cJSON_IsString(id) ? id->valuestring : "");
    pi->key = intern(&r->keys, &r->nkeys, k);
    pi->species = species_index(g, label, preset, idx);
    free(label);
    if (pi->plant < 0 || pi->key < 0) rc = nomem(g->err, g->errlen);
    else if (pi->species < 0) rc = SERVER_ENOMEM;
  }
  /* zones and solid boxes get their columns in scenario order, even when no stem ever
   * meets them (the planner reads "never" from an empty column) */
  if (!rc && sr->reports_conflicts) {
    cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(scen, "obstacles")) {
      const cJSON *id = cJSON_GetObjectItemCaseSensitive(e, "id");
      const cJSON *kind = cJSON_GetObjectItemCaseSensitive(e, "kind");
      if (!cJSON_IsString(id)) continue;
      bool zone = cJSON_IsString(kind) && strcmp(kind->valuestring, "zone") == 0;
      int k = zone ? intern(&r->zones, &r->nzones, id->valuestring)
                   : intern(&r->obstacles, &r->nobstacles, id->valuestring);
      if (k < 0) {
        rc = nomem(g->err, g->errlen);
        break;
      }
    }
  }
  size_t first_row = r->nrows;
  if (!rc && store_each_stats(st, sr->id, sr->last_iteration, on_stats, &p)) {
    rc = p.status ? p.status
                  : server_fail(g->err, g->errlen, SERVER_EFAIL, "%s", store_error(st));
  }
  if (!rc && r->shade) rc = run_shade(g, st, sr, scen, idx, first_row);
  free(p.slots);
  free(p.plant_info);
  cJSON_Delete(scen);
  cJSON_Delete(axes);
  return rc;
}

/* ---- the summary ---------------------------------------------------------------- */

static report_stat stat_of(double *v, int n) {
  report_stat s = {n, NAN, NAN, NAN};
  if (!n) return s;
  qsort(v, (size_t)n, sizeof *v, compare_doubles);
  s.min = v[0];
  s.max = v[n - 1];
  s.median = n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2.0;
  return s;
}

const char *const report_stand_columns[REPORT_STAND_FIGURES] = {
    "stems_per_ha", "basal_area", "qmd", "dominant_height", "sdi", "cv_dbh", "died"};
const char *const report_stand_heads[REPORT_STAND_FIGURES] = {
    "stems/ha", "basal area (m²/ha)", "QMD (cm)", "dominant height (m)", "SDI", "CV dbh",
    "died"};

bool report_measure_per_run(report_measure m) {
  return m == REPORT_CANOPY_COVER || m == REPORT_SHADE_GROUND;
}

int report_measures_shown(const report *r) {
  return r->shade ? REPORT_MEASURES : REPORT_SHADE_GROUND;
}

static double measure_of(const report_row *row, report_measure m) {
  switch (m) {
  case REPORT_HEIGHT: return row->height;
  case REPORT_DBH: return row->dbh;
  case REPORT_CROWN_DIAMETER: return row->crown_diameter;
  case REPORT_CROWN_HEIGHT: return row->crown_height;
  case REPORT_CO2: return row->co2;
  case REPORT_CANOPY_COVER: return row->canopy_cover;
  default: return row->shade_ground;
  }
}

/* Whether rows[idx[i]] is the first of idx[0..i] from its run (rows are by run, so a
 * run's rows in a group are consecutive). */
static bool first_of_run(const report *r, const size_t *idx, size_t i) {
  return i == 0 || r->rows[idx[i - 1]].run != r->rows[idx[i]].run;
}

/* Whether a row belongs to the group of axis a's value and species s at year y: for a
 * species axis only the plants of its key count. */
static bool in_group(const report *r, const report_row *row, int a, const char *value, int s,
                     int y) {
  if (row->year != y || row->species != s) return false;
  if (a < 0) return true;
  if (strcmp(r->runs[row->run].values[a], value) != 0) return false;
  if (strncmp(r->axes[a], "species/", 8) == 0)
    return strcmp(r->keys[row->key], r->axes[a] + 8) == 0;
  return true;
}

/* Adds the groups of axis a's value (a = -1: all runs) at every species and year; buf
 * and idx have room for every row. */
static int summarise_value(report *r, int a, const char *value, double *buf, size_t *idx,
                           size_t *cap, char *err, size_t errlen) {
  for (int s = 0; s < r->nspecies; s++)
    for (int y = 0; y < r->nyears; y++) {
      size_t n = 0;
      for (size_t i = 0; i < r->nrows; i++)
        if (in_group(r, &r->rows[i], a, value, s, y)) idx[n++] = i;
      if (!n) continue;
      if (!grow((void **)&r->groups, cap, r->ngroups + 1, sizeof *r->groups))
        return nomem(err, errlen);
      report_group *g = &r->groups[r->ngroups];
      *g = (report_group){.axis = a, .value = value, .species = s, .year = y, .n = (int)n};
      if (r->nzones) {
        g->first = calloc((size_t)r->nzones, sizeof *g->first);
        if (!g->first) return nomem(err, errlen);
      }
      r->ngroups++;
      for (size_t i = 0; i < n; i++) g->runs += first_of_run(r, idx, i);
      for (int m = 0; m < REPORT_MEASURES; m++) {
        /* a run's value is on each of its stems' rows: count it once */
        bool per_run = report_measure_per_run((report_measure)m);
        int k = 0;
        for (size_t i = 0; i < n; i++) {
          if (per_run && !first_of_run(r, idx, i)) continue;
          double v = measure_of(&r->rows[idx[i]], (report_measure)m);
          if (!isnan(v)) buf[k++] = v;
        }
        g->measure[m] = stat_of(buf, k);
      }
      for (int f = 0; f < REPORT_STAND_FIGURES; f++) { /* one value per run */
        int k = 0;
        for (size_t i = 0; i < n; i++) {
          double v = r->rows[idx[i]].stand[f];
          if (first_of_run(r, idx, i) && !isnan(v)) buf[k++] = v;
        }
        g->stand[f] = stat_of(buf, k);
      }
      for (int z = 0; z < r->nzones; z++) {
        int k = 0;
        for (size_t i = 0; i < n; i++) {
          const report_row *row = &r->rows[idx[i]];
          for (int j = 0; j < row->nfirst; j++)
            if (row->first[j].index == z) buf[k++] = row->first[j].value;
        }
        g->first[z] = stat_of(buf, k);
      }
    }
  return SERVER_OK;
}

static int summarise(report *r, char *err, size_t errlen) {
  double *buf = malloc((r->nrows ? r->nrows : 1) * sizeof *buf);
  size_t *idx = malloc((r->nrows ? r->nrows : 1) * sizeof *idx);
  if (!buf || !idx) {
    free(buf);
    free(idx);
    return nomem(err, errlen);
  }
  size_t cap = 0;
  int rc = SERVER_OK, axes = 0;
  /* the summary pools seeds: the seed axis is no grouping of its own */
  for (int a = 0; a < r->naxes && !rc; a++) {
    if (strcmp(r->axes[a], "seed") == 0) continue;
    axes++;
    for (int i = 0; i < r->nruns && !rc; i++) {
      const char *v = r->runs[i].values[a];
      bool seen = false;
      for (int j = 0; j < i && !seen; j++) seen = strcmp(r->runs[j].values[a], v) == 0;
      if (!seen) rc = summarise_value(r, a, v, buf, idx, &cap, err, errlen);
    }
  }
  if (!rc && !axes) rc = summarise_value(r, -1, "all runs", buf, idx, &cap, err, errlen);
  free(buf);
  free(idx);
  return rc;
}

/* The median age at planting of each species' stems (from their last rows). */
static int planting_ages(report *r, char *err, size_t errlen) {
  int *buf = malloc((r->nfinals ? r->nfinals : 1) * sizeof *buf);
  if (!buf) return nomem(err, errlen);
  for (int s = 0; s < r->nspecies; s++) {
    int n = 0;
    for (size_t i = 0; i < r->nfinals; i++)
      if (r->finals[i].species == s && r->finals[i].age >= 0)
        buf[n++] = r->finals[i].age - r->finals[i].iteration;
    qsort(buf, (size_t)n, sizeof *buf, compare_ints);
    r->species[s].age0 = n ? buf[(n - 1) / 2] : 0;
  }
  free(buf);
  return SERVER_OK;
}

/* ---- loading -------------------------------------------------------------------- */

static int compare_swept(const void *a, const void *b) {
  const swept *x = a, *y = b;
  return (x->position > y->position) - (x->position < y->position);
}

/* The sweep to report from the swept runs (q->sweep, or the only one); NULL when the
 * store has none. */
static int choose_sweep(const report_request *q, const swept_list *l, const char **out,
                        char *err, size_t errlen) {
  *out = NULL;
  char names[600];
  int count = sweep_names(l, names, sizeof names);
  if (q->sweep) {
    for (size_t i = 0; i < l->n; i++)
      if (strcmp(l->v[i].sweep, q->sweep) == 0) {
        *out = q->sweep;
        return SERVER_OK;
      }
    if (!count)
      return server_fail(err, errlen, SERVER_EINPUT, "%s: no sweep named \"%s\" (the store has no "
                  "sweeps)", q->db, q->sweep);
    return server_fail(err, errlen, SERVER_EINPUT, "%s: no sweep named \"%s\" (its sweeps: %s)", q->db,
                q->sweep, names);
  }
  if (count > 1)
    return server_fail(err, errlen, SERVER_EINPUT, "%s has %d sweeps (%s): choose one with --sweep NAME",
                q->db, count, names);
  if (count == 1) *out = l->v[0].sweep;
  return SERVER_OK;
}

/* The axes of the sweep, in the order its runs list them. */
static int sweep_axes(report *r, const swept_list *l, char *err, size_t errlen) {
  for (size_t i = 0; i < l->n; i++) {
    cJSON *o = cJSON_Parse(l->v[i].axes);
    if (!o)
      return server_fail(err, errlen, SERVER_EFAIL, "%s: the axes of run %lld are not JSON", r->db,
                  (long long)l->v[i].run);
    const cJSON *e;
    int rc = SERVER_OK;
    cJSON_ArrayForEach(e, o) {
      if (e->string && intern(&r->axes, &r->naxes, e->string) < 0) rc = nomem(err, errlen);
    }
    cJSON_Delete(o);
    if (rc) return rc;
  }
  return SERVER_OK;
}

static int load(store *st, const report_request *q, report *r, gather *g, char *err,
                size_t errlen) {
  swept_list l = {0};
  if (store_each_sweep_run(st, NULL, collect_swept, &l)) {
    int rc = l.oom ? nomem(err, errlen) : server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
    free_swept(&l);
    return rc;
  }
  const char *sweep;
  int rc = choose_sweep(q, &l, &sweep, err, errlen);
  if (!rc && sweep) {
    r->sweep = strdup(sweep);
    if (!r->sweep) rc = nomem(err, errlen);
    /* keep only this sweep's runs, in plan order */
    size_t n = 0;
    for (size_t i = 0; i < l.n; i++) {
      if (strcmp(l.v[i].sweep, sweep) == 0) {
        swept t = l.v[n];
        l.v[n++] = l.v[i];
        l.v[i] = t;
      }
    }
    for (size_t i = n; i < l.n; i++) {
      free(l.v[i].sweep);
      free(l.v[i].axes);
    }
    l.n = n;
    qsort(l.v, l.n, sizeof *l.v, compare_swept);
  }
  char *plan_text = NULL;
  if (!rc && sweep) {
    if (store_sweep_plan(st, sweep, &plan_text))
      rc = server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
    else if (plan_text && !(g->plan = cJSON_Parse(plan_text)))
      rc = server_fail(err, errlen, SERVER_EFAIL, "%s: the plan of sweep \"%s\" is not JSON", q->db,
                sweep);
    free(plan_text);
    char why[512];
    if (!rc && g->plan && sweep_plan_shade(g->plan, &r->shade, &r->shade_day, why, sizeof why))
      rc = server_fail(err, errlen, SERVER_EFAIL, "%s: the plan of sweep \"%s\": %s", q->db, sweep,
                       why);
  }
  if (!rc && sweep) rc = sweep_axes(r, &l, err, errlen);

  store_run *runs = NULL;
  size_t nruns = 0;
  if (!rc && store_list_runs(st, &runs, &nruns))
    rc = server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
  if (!rc && !nruns)
    rc = server_fail(err, errlen, SERVER_EINPUT, "%s: the store has no runs", q->db);
  if (!rc && sweep) {
    for (size_t i = 0; i < l.n && !rc; i++) {
      const store_run *sr = NULL;
      for (size_t j = 0; j < nruns && !sr; j++)
        if (runs[j].id == l.v[i].run) sr = &runs[j];
      if (sr) rc = gather_run(g, st, sr, l.v[i].axes, l.v[i].position);
    }
  } else if (!rc) {
    for (size_t j = 0; j < nruns && !rc; j++) rc = gather_run(g, st, &runs[j], NULL, -1);
  }
  store_runs_free(runs, nruns);
  free_swept(&l);
  return rc;
}

int report_load(store *st, const report_request *q, report **out, char *err, size_t errlen) {
  *out = NULL;
  report *r = calloc(1, sizeof *r);
  if (!r) return nomem(err, errlen);
  r->db = strdup(q->db ? q->db : "");
  if (!r->db) {
    free(r);
    return nomem(err, errlen);
  }
  r->nyears = q->nyears < REPORT_MAX_YEARS ? q->nyears : REPORT_MAX_YEARS;
  memcpy(r->years, q->years, (size_t)r->nyears * sizeof *r->years);
  gather g = {.r = r, .warn = q->warn, .err = err, .errlen = errlen};
  int rc = load(st, q, r, &g, err, errlen);
  if (!rc && g.no_site && q->warn) {
    char msg[600];
    snprintf(msg, sizeof msg, "%s: %d of %d runs (\"%.300s\"%s) have no light.latitude: their "
             "shade columns are empty", r->db, g.no_site, r->nruns, g.no_site_run,
             g.no_site > 1 ? ", ..." : "");
    q->warn(msg);
  }
  free(g.no_site_run);
  cJSON_Delete(g.plan);
  sylva_utdb_free(g.utdb);
  if (!rc) {
    r->common_start_year = r->nruns ? r->runs[0].start_year : 0;
    for (int i = 1; i < r->nruns; i++)
      if (r->runs[i].start_year != r->common_start_year) r->common_start_year = 0;
    rc = planting_ages(r, err, errlen);
  }
  if (!rc) rc = summarise(r, err, errlen);
  if (rc) {
    report_free(r);
    return rc;
  }
  *out = r;
  return SERVER_OK;
}
