/* The report as CSV: one row per run, stem and reported year (docs/cli.md, "report").
 * Numbers are written so that they read back as the stored doubles. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csv.h"
#include "report.h"

/* One field after a comma (none before the first), RFC 4180 quoted. */
static void put_field(FILE *f, const char *s, bool first) {
  if (!first) fputc(',', f);
  csv_write_text(f, s);
}

/* A field named prefix + name ("first_road"). */
static void put_named(FILE *f, const char *prefix, const char *name) {
  char buf[512];
  snprintf(buf, sizeof buf, "%s%s", prefix, name);
  put_field(f, buf, false);
}

static void put_number(FILE *f, double v) {
  char buf[40];
  report_format_number(buf, sizeof buf, v);
  put_field(f, buf, false);
}

static void put_int(FILE *f, long long v, bool present) {
  char buf[32];
  if (present) snprintf(buf, sizeof buf, "%lld", v);
  else buf[0] = '\0';
  put_field(f, buf, false);
}

/* The value of index i among a row's pairs; NAN when the row has none. */
static double pair_value(const report_kv *kv, int n, int i) {
  for (int j = 0; j < n; j++)
    if (kv[j].index == i) return kv[j].value;
  return NAN;
}

int report_write_csv(FILE *f, const report *r, char *err, size_t errlen) {
  put_field(f, "run", true);
  for (int a = 0; a < r->naxes; a++) put_field(f, r->axes[a], false);
  put_field(f, "plant", false);
  if (r->multi_stem) put_field(f, "stem", false);
  put_field(f, "species", false);
  put_field(f, "age", false);
  put_field(f, r->calendar ? "year" : "iteration", false);
  put_field(f, "height", false);
  put_field(f, "dbh", false);
  put_field(f, "crown_diameter", false);
  put_field(f, "crown_height", false);
  put_field(f, "leaf_area", false);
  put_field(f, "co2", false);
  put_field(f, "co2_sequestered", false);
  put_field(f, "canopy_cover", false);
  if (r->shade) {
    put_field(f, "shade_ground", false);
    for (int o = 0; o < r->nshade_obstacles; o++) put_named(f, "shade_", r->shade_obstacles[o]);
  }
  if (r->stand)
    for (int k = 0; k < REPORT_STAND_FIGURES; k++) put_field(f, report_stand_columns[k], false);
  for (int z = 0; z < r->nzones; z++) put_named(f, "first_", r->zones[z]);
  for (int o = 0; o < r->nobstacles; o++) put_named(f, "clearance_", r->obstacles[o]);
  if (r->conflicts) put_field(f, "pruned", false);
  fputc('\n', f);

  for (size_t i = 0; i < r->nrows; i++) {
    const report_row *row = &r->rows[i];
    const report_run *run = &r->runs[row->run];
    put_field(f, run->name, true);
    for (int a = 0; a < r->naxes; a++) put_field(f, run->values[a], false);
    put_field(f, r->plants[row->plant], false);
    if (r->multi_stem) put_int(f, row->stem, true);
    put_field(f, r->species[row->species].label, false);
    put_int(f, row->age, row->age >= 0);
    put_int(f, r->calendar ? (long long)run->start_year + row->iteration : row->iteration, true);
    put_number(f, row->height);
    put_number(f, row->dbh);
    put_number(f, row->crown_diameter);
    put_number(f, row->crown_height);
    put_number(f, row->leaf_area);
    put_number(f, row->co2);
    put_number(f, row->co2_sequestered);
    put_number(f, row->canopy_cover);
    if (r->shade) {
      const report_shade *sh = &run->shade[row->year];
      put_number(f, sh->ground);
      for (int o = 0; o < r->nshade_obstacles; o++)
        put_number(f, pair_value(sh->obstacles, sh->nobstacles, o));
    }
    if (r->stand)
      for (int k = 0; k < REPORT_STAND_FIGURES; k++) put_number(f, row->stand[k]);
    for (int z = 0; z < r->nzones; z++) put_number(f, pair_value(row->first, row->nfirst, z));
    for (int o = 0; o < r->nobstacles; o++)
      put_number(f, pair_value(row->clearance, row->nclearance, o));
    if (r->conflicts) put_int(f, row->pruned, row->pruned >= 0);
    fputc('\n', f);
  }
  if (fflush(f) || ferror(f)) {
    snprintf(err, errlen, "%s", strerror(errno ? errno : EIO));
    return SERVER_EWRITE;
  }
  return SERVER_OK;
}
