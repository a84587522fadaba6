/* libsylva-import: the measured trees of a scenario (a plant's "from", docs/scenario.md,
 * "Plants"), read from their files and built for the scenario's species. */
#ifndef SYLVA_IMPORT_MEASURED_H
#define SYLVA_IMPORT_MEASURED_H

#include <stddef.h>

#include "sylva/scenario.h"

/** The species' own height over age, from its growth equation: heights[a] =
 *  rho * X(t0 + a) for a = 0..years, t0 its nursery seasons (years species), made
 *  never decreasing. heights holds years + 1 values. */
void sylva_import_species_heights(const sylva_species_def *d, double *heights, int years);

/** The height curve a measured tree is dated on (docs/model.md, "Measured trees"):
 *  the species' own growth (sylva_import_species_heights) up to its oldest age, the
 *  first at which it is within 1% of its height at SYLVA_MAX_AGE, or `age` when that
 *  is older. heights holds SYLVA_MAX_AGE + 1 values; returns the last age. */
int sylva_import_curve(const sylva_species_def *d, int age, double *heights);

/** Reads every plant's "from" file of s (paths relative to the directory of
 *  scenario_path), builds the tree at the plant's root for its species (rho, pipe
 *  exponent, height curve) and gives the plant its nodes and age. 0, or a negative
 *  status with a message naming the plant (its JSON pointer), the file and the place. */
int sylva_import_measured(const char *scenario_path, sylva_scenario *s, char *err, size_t errlen);

#endif
