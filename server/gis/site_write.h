/* sylva gis: a site (site.h) written as a scenario (`sylva.scenario/1`,
 * docs/scenario.md) and as `sylva site`'s summary line (docs/cli.md, "site").
 * Numbers are written by one fixed formatter: lengths of the local frame in whole
 * millimetres as metres with at most 3 decimals, degrees and directions with at
 * most 6, trailing zeros dropped, so the same site always gives the same bytes. */
#ifndef SYLVA_GIS_SITE_WRITE_H
#define SYLVA_GIS_SITE_WRITE_H

#include "site.h"

/** What the scenario carries besides the site. */
typedef struct site_scenario {
  const char *name; /**< its "name" */
  int iterations;
  int start_year; /**< 0: none */
  double rho;     /**< > 0: each species planted gets "rho" (m) beside its preset */
} site_scenario;

/** The scenario as JSON text ending in a newline: malloc()ed, NULL when out of
 *  memory. */
char *site_scenario_json(const site *s, const site_scenario *sc);

/** The summary as one line of JSON without a newline: malloc()ed, NULL when out of
 *  memory. */
char *site_summary_json(const site *s);

#endif
