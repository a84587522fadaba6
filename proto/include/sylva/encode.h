/* sylva: deterministic JSON encoders (the same input gives the same bytes). */
#ifndef SYLVA_ENCODE_H
#define SYLVA_ENCODE_H

#include <stdbool.h>
#include <stddef.h>

#include "sylva/world.h"

/** A buffer this large holds any number sylva_fmt_* can write. */
#define SYLVA_FMT_BUFSIZE 400

/** Formats v with `decimals` (0..17) fixed decimals, then trims trailing zeros and a
 *  trailing '.': 1.9000 -> "1.9", 2.0 -> "2". A result of "-0" prints "0"; NaN and
 *  infinities print "null". Returns the length of the full text (like snprintf);
 *  the text is truncated when it does not fit in n bytes. */
int sylva_fmt_fixed(char *buf, size_t n, double v, int decimals);

/** Formats v with the fewest significant digits (up to 17) that read back as the
 *  same double ("0.1", "1e-07", "12"); -0 prints "0", non-finite values "null".
 *  Returns the length like snprintf. */
int sylva_fmt_shortest(char *buf, size_t n, double v);

/** Whether the stats of w carry the measures of real species (cli.md): `age`,
 *  `crown_diameter` and `crown_height`, because some species of w counts in years. */
bool sylva_encode_years(const sylva_world *w);
/** Do w's lines give alive, died and vigour per stem and the stand's figures
 *  (docs/model.md, "Stands")? A world with a species in years or with deaths. */
bool sylva_encode_stand(const sylva_world *w);

/** One of the stand's figures as the lines give it (docs/model.md, "Stands"): its key
 *  in the stand object, its value (NaN: null) and its decimals. */
typedef struct sylva_stand_figure {
  const char *key;
  double value;
  int decimals;
} sylva_stand_figure;
/** How many figures sylva_stand_figures gives. */
#define SYLVA_STAND_FIGURES 7
/** The stand's figures after its area, alive and died, in the lines' order:
 *  stems_per_ha, basal_area, qmd, dominant_height, sdi, cv_height, cv_dbh. */
void sylva_stand_figures(const sylva_stand_stats *s, sylva_stand_figure out[SYLVA_STAND_FIGURES]);

/** One line of `sylva run` (cli.md), without the newline:
 *  {"iteration": 7, "elapsed_ms": 12.5, "stems": [{"plant": "t1", "stem": 0, ...}]}
 *  Stems in global stem order (j->stats); NaN measures print null; lengths with 4
 *  decimals, leaf_area (m^2, after crown_base or crown_height) with 4, light with 3,
 *  elapsed_ms with 1, all trimmed. In a world that reports
 *  conflicts each stem has pruned, zones and clearance; in one with years
 *  (sylva_encode_years) age, crown_diameter and crown_height. start_year (0: none)
 *  adds "year" (start_year + iteration) after "iteration" and dates the zones'
 *  "first" in calendar years. Returns a malloc'd string, NULL when out of memory. */
char *sylva_encode_stats_line(const sylva_world *w, const sylva_journal *j, double elapsed_ms,
                              int start_year);

/** One global stem's zones (`{"road":{"nodes":3,"first":7}}`, "first" in calendar
 *  years with a start_year, else in iterations) or, with clearance, its clearances
 *  (`{"wall":1.25}`), as in the stats lines but compact. malloc'd; NULL when out of
 *  memory. */
char *sylva_encode_stem_conflicts(const sylva_world *w, int stem, bool clearance, int start_year);

/** The last line of `sylva run`, without the newline:
 *  {"done": true, "iterations": 24, "reason": "finished"}. malloc'd; NULL when out
 *  of memory. */
char *sylva_encode_done_line(int iterations, const char *reason);

/** The whole skeleton of w in the `sylva.skeleton/1` format of cli.md, compact,
 *  ending with a newline. Positions with 4 decimals, radii with 5. malloc'd; NULL
 *  when out of memory. */
char *sylva_encode_skeleton(const sylva_world *w);

#endif
