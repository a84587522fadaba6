#include "measured.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qsm.h"
#include "sylva/equations.h"
#include "sylva/status.h"
#include "tree.h"

void sylva_import_species_heights(const sylva_species_def *d, double *heights, int years) {
  int t0 = d->years ? d->nursery : 0;
  double top = 0.0;
  for (int a = 0; a <= years; a++) {
    double h = d->rho * sylva_equation_value(&d->growth, (double)(t0 + a));
    if (!(h > top)) h = top; /* never decreasing */
    heights[a] = top = h;
  }
}

int sylva_import_curve(const sylva_species_def *d, int age, double *heights) {
  sylva_import_species_heights(d, heights, SYLVA_MAX_AGE);
  /* the curve's oldest age: where it is within 1% of its end, growing no more */
  int a = 1;
  while (a < SYLVA_MAX_AGE && heights[a] < 0.99 * heights[SYLVA_MAX_AGE]) a++;
  return age > a ? age : a;
}

/* The file's path: as given when absolute, else beside the scenario. */
static char *resolve(const char *scenario_path, const char *file) {
  if (file[0] == '/') return strdup(file);
  const char *slash = strrchr(scenario_path, '/');
  size_t dir = slash ? (size_t)(slash - scenario_path) + 1 : 0;
  char *out = malloc(dir + strlen(file) + 1);
  if (!out) return NULL;
  memcpy(out, scenario_path, dir);
  strcpy(out + dir, file);
  return out;
}

static int read_plant(const char *scenario_path, const sylva_scenario *s, int i, char *err,
                      size_t errlen) {
  sylva_scenario_plant *pl = &s->plants[i];
  const sylva_species_def *d = &s->species[pl->species].def;
  char *path = resolve(scenario_path, pl->from_file);
  if (!path) return SYLVA_ENOMEM;
  char why[1024];
  sylva_qsm q = {0};
  int rc = sylva_qsm_read(path, sylva_qsm_format_named(pl->from_format), pl->from_model, &q, why,
                          sizeof why);
  double *heights = NULL;
  sylva_tree t = {0};
  int years = 0;
  if (!rc && !(heights = malloc((size_t)(SYLVA_MAX_AGE + 1) * sizeof *heights))) rc = SYLVA_ENOMEM;
  if (!rc) {
    years = sylva_import_curve(d, pl->from_age, heights);
    sylva_tree_options o = {.rho = d->rho, .heights = heights, .years = years,
                            .age = pl->from_age > 0 ? pl->from_age : 0,
                            .pipe_exponent = d->pipe_exponent};
    memcpy(o.base, pl->roots[0], sizeof o.base);
    rc = sylva_tree_build(&q, &o, &t, why, sizeof why);
  }
  if (!rc && t.count > (size_t)SYLVA_MAX_MEASURED_NODES) {
    snprintf(why, sizeof why, "%zu nodes: at most %d", t.count, SYLVA_MAX_MEASURED_NODES);
    rc = SYLVA_ETOOBIG;
  }
  if (!rc && !(pl->nodes = calloc(t.count, sizeof *pl->nodes))) rc = SYLVA_ENOMEM;
  if (!rc) {
    for (size_t k = 0; k < t.count; k++) {
      const sylva_tree_node *n = &t.node[k];
      pl->nodes[k] = (sylva_plant_node){{n->p[0], n->p[1], n->p[2]}, n->radius, n->parent,
                                        n->lateral, n->birth};
    }
    pl->node_count = (int)t.count;
    pl->measured_age = d->years ? t.age : 0;
  }
  if (rc)
    snprintf(err, errlen, "/plants/%d/from: %s: %s", i, pl->from_file,
             rc == SYLVA_ENOMEM ? "out of memory" : why);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
  free(heights);
  free(path);
  return rc;
}

int sylva_import_measured(const char *scenario_path, sylva_scenario *s, char *err, size_t errlen) {
  for (int i = 0; i < s->plant_count; i++)
    if (s->plants[i].from_file && !s->plants[i].nodes) {
      int rc = read_plant(scenario_path, s, i, err, errlen);
      if (rc) return rc;
    }
  return SYLVA_OK;
}
