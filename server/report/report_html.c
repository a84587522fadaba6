/* The report as one self-contained HTML page: the summary table, each species drawn
 * at each reported year, the plots and the first-conflict chart, every picture a PNG
 * inlined as a data: URI (base64 by libwebsockets, which the daemon links already). */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libwebsockets.h>

#include "report.h"
#include "report_draw.h"

#define PLOT_WIDTH 1000
#define PLOT_HEIGHT 440

/* Text with the characters HTML gives a meaning escaped. */
static void put_text(FILE *f, const char *s) {
  for (; *s; s++) {
    switch (*s) {
    case '&': fputs("&amp;", f); break;
    case '<': fputs("&lt;", f); break;
    case '>': fputs("&gt;", f); break;
    case '"': fputs("&quot;", f); break;
    default: fputc(*s, f);
    }
  }
}

/* An <img> with the PNG inline. */
static int put_png(FILE *f, const report_png *p, const char *alt, char *err, size_t errlen) {
  if (p->len > (size_t)INT_MAX / 2) {
    snprintf(err, errlen, "a picture of %zu bytes is too large to inline", p->len);
    return SERVER_EFAIL;
  }
  /* libwebsockets wants room for a whole group and the terminator at each step */
  size_t cap = (p->len + 2) / 3 * 4 + 8;
  char *b64 = malloc(cap);
  if (!b64) {
    snprintf(err, errlen, "out of memory");
    return SERVER_ENOMEM;
  }
  int n = lws_b64_encode_string((const char *)p->data, (int)p->len, b64, (int)cap);
  if (n < 0) {
    free(b64);
    snprintf(err, errlen, "encoding a picture as base64 failed");
    return SERVER_EFAIL;
  }
  fprintf(f, "<img width=\"%d\" height=\"%d\" alt=\"", p->width, p->height);
  put_text(f, alt);
  fputs("\" src=\"data:image/png;base64,", f);
  fwrite(b64, 1, (size_t)n, f);
  fputs("\">", f);
  free(b64);
  return SERVER_OK;
}

static const char *const measure_heads[REPORT_MEASURES] = {
    "height (m)", "dbh (m)", "crown diameter (m)", "crown height (m)", "CO2 (kg)",
    "canopy cover", "tree shade, ground (h)"};

/* A group's first cells: its axis, value, species and year. */
static void put_group_cells(FILE *f, const report *r, const report_group *g) {
  char cell[64];
  fputs("<tr><td>", f);
  put_text(f, report_group_axis(r, g));
  fputs("</td><td>", f);
  put_text(f, g->value);
  fputs("</td><td>", f);
  put_text(f, r->species[g->species].label);
  report_format_year(cell, sizeof cell, r, g->year);
  fprintf(f, "</td><td>%s</td>", cell);
}

/* The head of a table of the groups, of class cls, up to its year column. */
static void put_group_head(FILE *f, const char *cls) {
  fprintf(f, "<table class=\"%s\">\n<thead><tr><th>axis</th><th>value</th><th>species</th>"
             "<th>years</th>",
          cls);
}

static void put_summary(FILE *f, const report *r) {
  put_group_head(f, "summary");
  fputs("<th>stems</th>", f);
  for (int m = 0; m < report_measures_shown(r); m++)
    fprintf(f, "<th>%s</th>", measure_heads[m]);
  for (int z = 0; z < r->nzones; z++) {
    fputs("<th>first conflict: ", f);
    put_text(f, r->zones[z]);
    fputs("</th>", f);
  }
  fputs("</tr></thead>\n<tbody>\n", f);
  char cell[160];
  for (size_t i = 0; i < r->ngroups; i++) {
    const report_group *g = &r->groups[i];
    put_group_cells(f, r, g);
    fprintf(f, "<td>%d</td>", g->n);
    for (int m = 0; m < report_measures_shown(r); m++) {
      report_format_stat(cell, sizeof cell, &g->measure[m],
                         report_measure_per_run((report_measure)m) ? g->runs : g->n);
      fprintf(f, "<td>%s</td>", cell);
    }
    for (int z = 0; z < r->nzones; z++) {
      report_format_first(cell, sizeof cell, &g->first[z], g->n);
      fprintf(f, "<td>%s</td>", cell);
    }
    fputs("</tr>\n", f);
  }
  fputs("</tbody></table>\n", f);
}

/* The stand's figures of each group, over its runs (docs/cli.md, "report"). */
static void put_stand(FILE *f, const report *r) {
  put_group_head(f, "stand");
  fputs("<th>runs</th>", f);
  for (int k = 0; k < REPORT_STAND_FIGURES; k++) fprintf(f, "<th>%s</th>", report_stand_heads[k]);
  fputs("</tr></thead>\n<tbody>\n", f);
  char cell[160];
  for (size_t i = 0; i < r->ngroups; i++) {
    const report_group *g = &r->groups[i];
    put_group_cells(f, r, g);
    fprintf(f, "<td>%d</td>", g->runs);
    for (int k = 0; k < REPORT_STAND_FIGURES; k++) {
      report_format_stat(cell, sizeof cell, &g->stand[k], g->runs);
      fprintf(f, "<td>%s</td>", cell);
    }
    fputs("</tr>\n", f);
  }
  fputs("</tbody></table>\n", f);
}

static int put_pictures(FILE *f, store *st, const report *r, const report_draw_options *o,
                        char *err, size_t errlen) {
  fputs("<table class=\"pictures\">\n<tr><th>species</th>", f);
  char cell[64];
  for (int y = 0; y < r->nyears; y++) {
    report_format_year(cell, sizeof cell, r, y);
    fprintf(f, "<th>year %s</th>", cell);
  }
  fputs("</tr>\n", f);
  for (int s = 0; s < r->nspecies; s++) {
    fputs("<tr><th>", f);
    put_text(f, r->species[s].label);
    fputs("<br><small>", f);
    put_text(f, r->runs[r->species[s].picture_run].name);
    fputs("</small></th>", f);
    for (int y = 0; y < r->nyears; y++) {
      fputs("<td>", f);
      if (report_has_picture(r, s, y)) {
        report_png p;
        int rc = report_picture(st, r, s, y, o, &p, err, errlen);
        if (rc) return rc;
        char alt[300];
        snprintf(alt, sizeof alt, "%s at year %d", r->species[s].label, r->years[y]);
        rc = put_png(f, &p, alt, err, errlen);
        report_png_free(&p);
        if (rc) return rc;
      } else {
        fputs("not grown so far", f);
      }
      fputs("</td>", f);
    }
    fputs("</tr>\n", f);
  }
  fputs("</table>\n", f);
  return SERVER_OK;
}

static int put_figure(FILE *f, const report *r, int m, int h, const char *alt, char *err,
                      size_t errlen) {
  report_png p;
  int rc = report_figure_png(r, m, PLOT_WIDTH, h, &p, err, errlen);
  if (!rc) rc = put_png(f, &p, alt, err, errlen);
  report_png_free(&p);
  fputs("\n", f);
  return rc;
}

static void put_runs(FILE *f, const report *r) {
  fputs("<table class=\"runs\">\n<thead><tr><th>run</th>", f);
  for (int a = 0; a < r->naxes; a++) {
    fputs("<th>", f);
    put_text(f, r->axes[a]);
    fputs("</th>", f);
  }
  fputs("<th>last iteration</th></tr></thead>\n<tbody>\n", f);
  for (int i = 0; i < r->nruns; i++) {
    fputs("<tr><td>", f);
    put_text(f, r->runs[i].name);
    fputs("</td>", f);
    for (int a = 0; a < r->naxes; a++) {
      fputs("<td>", f);
      put_text(f, r->runs[i].values[a]);
      fputs("</td>", f);
    }
    fprintf(f, "<td>%d</td></tr>\n", r->runs[i].last_iteration);
  }
  fputs("</tbody></table>\n", f);
}

int report_write_html(FILE *f, store *st, const report *r, const report_draw_options *o,
                      char *err, size_t errlen) {
  const char *what = r->sweep ? r->sweep : "the runs of the store";
  fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>sylva "
        "report: ",
        f);
  put_text(f, what);
  fputs("</title>\n<style>\n"
        "body { font-family: sans-serif; margin: 2em; color: #222; }\n"
        "table { border-collapse: collapse; margin: 1em 0; }\n"
        "th, td { border: 1px solid #bbb; padding: 0.25em 0.5em; text-align: left; "
        "vertical-align: top; }\n"
        "table.summary td, table.stand td { white-space: nowrap; font-variant-numeric: tabular-nums; }\n"
        "table.pictures img { max-width: 520px; height: auto; }\n"
        "img { max-width: 100%; height: auto; }\n"
        "p.note { color: #555; max-width: 60em; }\n"
        "</style>\n</head>\n<body>\n<h1>sylva report: ",
        f);
  put_text(f, what);
  fputs("</h1>\n<p>Store <code>", f);
  put_text(f, r->db);
  fprintf(f, "</code>: %d run%s; reported years:", r->nruns, r->nruns == 1 ? "" : "s");
  char cell[64];
  for (int y = 0; y < r->nyears; y++) {
    report_format_year(cell, sizeof cell, r, y);
    fprintf(f, "%s %s", y ? "," : "", cell);
  }
  fputs(" (years since planting, the stats of that iteration).</p>\n", f);

  fputs("<h2>Summary</h2>\n<p class=\"note\">Per axis value, the seeds (and plants) pooled: "
        "median (minimum–maximum) over the stems, in metres and kilograms as stored; canopy "
        "cover (the share of open ground under leaves) over the runs, one value each; \"k of n\" "
        "where only k of the n stems (runs) have a value. First conflict: the stored first year in each zone "
        "(calendar years with a start year) of the stems that met it by that year.</p>\n",
        f);
  if (r->shade)
    fprintf(f, "<p class=\"note\">Tree shade, ground: per run, the mean hours of direct sun "
               "its trees take from the ground's cells on %02d-%02d from %02d:%02d to %02d:%02d "
               "(samples every %d minutes; <code>sylva shade</code>'s "
               "<code>tree_shade_hours</code>).</p>\n",
            r->shade_day.month, r->shade_day.day, r->shade_day.from / 60, r->shade_day.from % 60,
            r->shade_day.to / 60, r->shade_day.to % 60, r->shade_day.step);
  put_summary(f, r);
  if (!r->ngroups)
    fputs("<p>No run has reached any of the reported years.</p>\n", f);
  if (r->stand && r->ngroups) {
    fputs("<h2>Stand</h2>\n<p class=\"note\">The stand of each run (all its stems, per "
          "hectare of its stand area) at that year, over the runs of each summary line, one "
          "value each: median (minimum–maximum), \"k of n\" where only k of the n runs have a "
          "value. Died: the stems that died in iterations 1 to that year.</p>\n",
          f);
    put_stand(f, r);
  }

  fputs("<h2>Pictures</h2>\n<p class=\"note\">Each species in the first run that grows it, "
        "at each reported year.</p>\n",
        f);
  int rc = put_pictures(f, st, r, o, err, errlen);
  if (!rc) {
    fputs("<h2>Growth</h2>\n", f);
    rc = put_figure(f, r, REPORT_HEIGHT, PLOT_HEIGHT, "height over the years", err, errlen);
  }
  if (!rc)
    rc = put_figure(f, r, REPORT_CROWN_DIAMETER, PLOT_HEIGHT, "crown diameter over the years",
                    err, errlen);
  if (!rc) {
    fputs("<h2>First conflicts</h2>\n", f);
    rc = put_figure(f, r, -1, (int)report_conflicts_height(r), "first conflicts", err, errlen);
  }
  if (!rc) {
    fputs("<h2>Runs</h2>\n", f);
    put_runs(f, r);
    fputs("</body>\n</html>\n", f);
    if (fflush(f) || ferror(f)) {
      snprintf(err, errlen, "%s", strerror(errno ? errno : EIO));
      rc = SERVER_EWRITE;
    }
  }
  return rc;
}
