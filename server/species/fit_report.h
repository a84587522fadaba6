/* sylva species: the report of a calibration (`sylva fit`). */
#ifndef SYLVA_SPECIES_FIT_REPORT_H
#define SYLVA_SPECIES_FIT_REPORT_H

#include <stdio.h>

#include "fit.h"

/** A Markdown table of the data against the model at each decade within the data. */
void sylva_fit_report_table(FILE *f, const sylva_fit_targets *t, const sylva_fit_result *r);

/** A PNG of the four curves, data and model, with the measured trees (count may be
 *  0); 0 or -1 when the file could not be written. */
int sylva_fit_report_png(const char *path, const char *title, const sylva_fit_targets *t,
                         const sylva_fit_result *r, const sylva_fit_tree *trees, int count);

#endif
