/* Species presets: the rows of IGM Table 2 (docs/model.md, "Fidelity"), plus the
 * project's calibrated values of the keys the paper does not have. What neither
 * gives takes the defaults of sylva_default_species_def(). Names that start with
 * "utdb:" are the species library's (sylva/library.h, docs/species.md). */
#include <string.h>

#include "sylva/library.h"
#include "sylva/scenario.h"
#include "sylva/status.h"

typedef struct preset_row {
  const char *name;
  double lambda, k;
  int tau;
  double rho, x0, xm, r, alpha, sigma, mu, gamma, b_min, b_max, r_s;
  /* calibrated, not in Table 2: each tree alone measures like its row's result */
  double apical_flow, node_cost, shade_spread;
  int apical_zone;
  double r_tip, theta;
} preset_row;

static const preset_row presets[] = {
    {"igm-fig11", 0.52, 0.5, 6, 0.10, 2, 100, 0.34, 4, 0.5, 1.5, 0.5, 1.8, 2.2, 0.25,
     0.0, 1.5, 0.75, 12, 0.012, 45},
    {"igm-fig12", 0.54, 0.35, 6, 0.10, 2, 100, 0.34, 4, 0.5, 1.5, 0.5, 1.8, 2.2, 0.35,
     0.0, 1, 0.75, 12, 0.014, 45},
    {"igm-fig13", 0.52, 0.5, 5, 0.10, 2, 100, 0.34, 4, 0.5, 1.5, 0.5, 1.8, 2.3, 0.35,
     0.01, 1, 0.75, 12, 0.012, 45},
    {"igm-fig14-shrub", 0.46, 0.5, 0, 0.02, 2, 50, 0.34, 6, 1.0, 0.6, 1.0, 2.0, 2.5, 0.15,
     0.02, 2.5, 0.75, 0, 0.008, 135},
    {"igm-fig15-left", 0.48, 0.5, 4, 0.10, 2, 70, 0.34, 3, 0.5, 1.5, 0.5, 1.8, 2.5, 0.20,
     0.02, 1, 0.75, 8, 0.012, 45},
    {"igm-fig15-right", 0.52, 0.5, 4, 0.10, 2, 100, 0.34, 4, 0.5, 1.0, 0.2, 1.8, 2.2, 0.35,
     0.015, 1, 0.75, 12, 0.010, 45},
    {"igm-fig17b", 0.52, 0.5, 6, 0.10, 2, 100, 0.34, 4, 0.5, 1.0, 0.5, 1.8, 2.2, 0.35,
     0.0, 1, 0.65, 12, 0.017, 45},
    {"igm-fig18-broadleaf", 0.48, 0.5, 2, 0.10, 2, 100, 0.34, 6, 0.5, 1.0, 0.5, 1.8, 2.5, 0.25,
     0.02, 3, 0.75, 12, 0.008, 45},
    {"igm-fig18-shrub", 0.46, 0.5, 0, 0.01, 2, 50, 0.34, 6, 1.0, 1.0, 0.2, 2.0, 2.5, 0.05,
     0.02, 2.5, 0.75, 0, 0.008, 45},
    {"igm-fig18-cypress", 0.56, 0.5, 14, 0.20, 2, 100, 0.34, 3, 0.5, 0.5, 1.5, 1.8, 2.2, 0.45,
     0.02, 1.8, 0.25, 4, 0.025, 45},
};

#define PRESET_COUNT ((int)(sizeof presets / sizeof presets[0]))

int sylva_preset_count(void) { return PRESET_COUNT; }

const char *sylva_preset_name(int i) { return i >= 0 && i < PRESET_COUNT ? presets[i].name : NULL; }

int sylva_preset_find(const char *name, sylva_species_def *out) {
  if (strncmp(name, SYLVA_LIBRARY_PREFIX, strlen(SYLVA_LIBRARY_PREFIX)) == 0)
    return sylva_library_find(name, out);
  for (int i = 0; i < PRESET_COUNT; i++) {
    const preset_row *p = &presets[i];
    if (strcmp(p->name, name) != 0) continue;
    sylva_species_def d = sylva_default_species_def();
    d.lambda = p->lambda;
    d.k = p->k;
    d.tau = p->tau;
    d.rho = p->rho;
    d.growth.kind = SYLVA_EQ_LOGISTIC;
    d.growth.p[0] = p->x0;
    d.growth.p[1] = p->xm;
    d.growth.p[2] = p->r;
    d.alpha = p->alpha;
    d.sigma = p->sigma;
    d.mu = p->mu;
    d.gamma = p->gamma;
    d.b_min = p->b_min;
    d.b_max = p->b_max;
    d.r_s = p->r_s;
    d.initial_nodes = 2; /* round(X0) */
    d.apical_flow = p->apical_flow;
    d.node_cost = p->node_cost;
    d.shade_spread = p->shade_spread;
    d.apical_zone = p->apical_zone;
    d.r_tip = p->r_tip;
    d.theta = p->theta;
    if (out) *out = d;
    return 0;
  }
  return SYLVA_ENOTFOUND;
}
