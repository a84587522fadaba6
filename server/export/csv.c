#include "csv.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "sylva/encode.h"

void csv_write_text(FILE *f, const char *s) {
  if (!strpbrk(s, ",\"\r\n")) {
    fputs(s, f);
    return;
  }
  fputc('"', f);
  for (; *s; s++) {
    if (*s == '"') fputc('"', f);
    fputc(*s, f);
  }
  fputc('"', f);
}

static void csv_number(FILE *f, double v, int decimals) {
  if (isnan(v)) return; /* null: an empty field */
  char buf[64];
  sylva_fmt_fixed(buf, sizeof buf, v, decimals);
  fputs(buf, f);
}

/* What the rows of one run carry beyond the columns of every run. */
typedef struct csv_run {
  FILE *f;
  int start_year; /* 0: none */
  bool years;     /* a species counts in years */
  bool stand;     /* the rows carry the stand's (store_run_stand) */
} csv_run;

static int csv_row(const store_stats_row *r, void *ctx) {
  const csv_run *c = ctx;
  FILE *f = c->f;
  fprintf(f, "%d,", r->iteration);
  csv_write_text(f, r->plant);
  fprintf(f, ",%d,", r->plant_stem);
  csv_number(f, r->height, 4);
  fputc(',', f);
  csv_number(f, r->dbh, 4);
  fputc(',', f);
  csv_number(f, r->crown_width, 4);
  fputc(',', f);
  csv_number(f, r->crown_base, 4);
  fprintf(f, ",%lld,%lld,", (long long)r->nodes, (long long)r->shed);
  csv_number(f, r->light, 3);
  fprintf(f, ",%d,%s,", r->cap, r->finished ? "true" : "false");
  /* conflicts: empty where the run does not report them */
  if (r->pruned >= 0) fprintf(f, "%lld", (long long)r->pruned);
  fputc(',', f);
  if (r->zones) csv_write_text(f, r->zones);
  fputc(',', f);
  if (r->clearance) csv_write_text(f, r->clearance);
  fputc(',', f);
  csv_number(f, r->leaf_area, 4); /* empty in rows stored before schema 5 */
  /* years: empty where the run's lines lack the field or have null */
  if (c->years || c->start_year) {
    fputc(',', f);
    if (r->age >= 0) fprintf(f, "%d", r->age);
    fputc(',', f);
    if (c->start_year) fprintf(f, "%d", c->start_year + r->iteration);
    fputc(',', f);
    if (c->years) csv_number(f, r->crown_width, 4);
    fputc(',', f);
    if (c->years) csv_number(f, r->crown_height, 4);
  }
  /* what the trees give (docs/model.md): empty in rows stored before schema 6 and
   * where a measure does not apply */
  const struct {
    double v;
    int decimals;
  } give[] = {{r->crown_area, 4}, {r->wood_volume, 6}, {r->biomass, 3},
              {r->biomass_model, 3}, {r->carbon, 3}, {r->co2, 3},
              {r->co2_sequestered, 3}, {r->canopy_cover, 4}};
  for (size_t i = 0; i < sizeof give / sizeof *give; i++) {
    fputc(',', f);
    csv_number(f, give[i].v, give[i].decimals);
  }
  /* stands (docs/model.md, "Stands"): as the lines give them, empty in rows stored
   * before schema 7; died a calendar year in a run with a start year, as on the lines */
  if (c->stand) {
    fputs(r->alive < 0 ? "," : r->alive ? ",true" : ",false", f);
    fputc(',', f);
    if (r->died >= 0) fprintf(f, "%d", r->died + c->start_year);
    fputc(',', f);
    csv_number(f, r->vigour, 4);
    sylva_stand_figure fig[SYLVA_STAND_FIGURES];
    sylva_stand_figures(&r->stand, fig);
    for (size_t i = 0; i < SYLVA_STAND_FIGURES; i++) {
      fputc(',', f);
      csv_number(f, fig[i].value, fig[i].decimals);
    }
    fputc(',', f);
    if (r->stand.died >= 0) fprintf(f, "%d", r->stand.died);
  }
  fputc('\n', f);
  return ferror(f) ? SERVER_EWRITE : SERVER_OK;
}

int csv_write_stats(FILE *f, store *st, int64_t run, int to) {
  csv_run c = {f, 0, false, false};
  if (store_run_calendar(st, run, &c.start_year, &c.years) || store_run_stand(st, run, &c.stand))
    return SERVER_EFAIL;
  fputs("iteration,plant,stem,height,dbh,crown_width,crown_base,nodes,shed,light,cap,finished,"
        "pruned,zones,clearance,leaf_area",
        f);
  /* only in runs with years or a start year: the others keep the columns they had */
  fputs(c.years || c.start_year ? ",age,year,crown_diameter,crown_height" : "", f);
  fputs(",crown_area,wood_volume,biomass,biomass_model,carbon,co2,co2_sequestered,canopy_cover",
        f);
  /* only in runs with stands: the others keep their bytes */
  fputs(c.stand ? ",alive,died,vigour,stems_per_ha,basal_area,qmd,dominant_height,sdi,cv_height,"
                  "cv_dbh,stand_died\n"
                : "\n",
        f);
  if (ferror(f)) return SERVER_EWRITE;
  return store_each_stats(st, run, to, csv_row, &c);
}
