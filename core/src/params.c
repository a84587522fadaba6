#include "sylva/params.h"
#include "sylva/status.h"

#include <math.h>

sylva_species_def sylva_default_species_def(void) {
  sylva_species_def d = {
      .rho = 0.1,
      .growth = {SYLVA_EQ_LOGISTIC, {2.0, 100.0, 0.34}},
      .allocation = SYLVA_ALLOC_LGTM,
      .sprout_light = 0.5,
      .lambda = 0.52,
      .k = 0.5,
      .w1 = 1.0, .w2 = 0.6, .w3 = 0.3,
      .tau = 6,
      .alpha = 4.0,
      .leaf_age = 3,
      .node_cost = 1.0,
      .apical_zone = 12,
      .apical_flow = 0.02,
      .sigma = 0.5,
      .mu = 1.5,
      .gamma = 0.5,
      .tropism = {0.0, 0.0, 1.0},
      .theta = 45.0,
      .divergence = 137.5,
      .b_min = 1.8, .b_max = 2.2,
      .pyramid_depth = 20,
      .shade_spread = 0.75,
      .shade_column = 0.002,
      .r_s = 0.35,
      .r_tip = 0.012,
      .pipe_exponent = 2.5,
      .m0 = 20, .m_min = 4,
      .cone_angle = 60.0,
      .cone_radius = 4.0,
      .initial_nodes = 2,
  };
  return d;
}

static bool finite_in(double v, double lo, double hi) { return isfinite(v) && v >= lo && v <= hi; }

int sylva_species_check(const sylva_species_def *d, const char **field) {
#define SYLVA__REQUIRE(cond, name)                                                         \
  do {                                                                                     \
    if (!(cond)) {                                                                         \
      if (field) *field = name;                                                            \
      return SYLVA_ERANGE;                                                                 \
    }                                                                                      \
  } while (0)
  SYLVA__REQUIRE(finite_in(d->rho, 1e-4, 100.0), "rho");
  SYLVA__REQUIRE((unsigned)d->growth.kind < SYLVA_EQ_COUNT, "growth");
  for (int i = 0; i < 3; i++) SYLVA__REQUIRE(isfinite(d->growth.p[i]), "growth");
  switch (d->growth.kind) {
  case SYLVA_EQ_LOGISTIC:
    SYLVA__REQUIRE(d->growth.p[0] > 0 && d->growth.p[1] > d->growth.p[0] && d->growth.p[2] > 0,
                   "growth");
    break;
  case SYLVA_EQ_BERTALANFFY:
    SYLVA__REQUIRE(d->growth.p[0] > 0 && d->growth.p[1] > 0, "growth");
    break;
  default:
    SYLVA__REQUIRE(d->growth.p[0] > 0 && d->growth.p[1] > 0 && d->growth.p[2] > 0, "growth");
    break;
  }
  SYLVA__REQUIRE(sylva_equation_limit(&d->growth) <= 1e6, "growth");
  SYLVA__REQUIRE(d->allocation == SYLVA_ALLOC_LGTM || d->allocation == SYLVA_ALLOC_NONE,
                 "allocation");
  SYLVA__REQUIRE(finite_in(d->sprout_light, 0.0, 1.0), "sprout_light");
  SYLVA__REQUIRE(finite_in(d->lambda, 0.0, 1.0) && d->lambda > 0.0 && d->lambda < 1.0, "lambda");
  SYLVA__REQUIRE(finite_in(d->k, 0.0, 1.0), "k");
  SYLVA__REQUIRE(finite_in(d->w1, 0.0, 1e6), "w1");
  SYLVA__REQUIRE(finite_in(d->w2, 0.0, 1e6), "w2");
  SYLVA__REQUIRE(finite_in(d->w3, 0.0, 1e6), "w3");
  SYLVA__REQUIRE(d->tau >= 0 && d->tau <= 100000, "tau");
  SYLVA__REQUIRE(finite_in(d->alpha, 0.0, 1e6) && d->alpha > 0.0, "alpha");
  SYLVA__REQUIRE(finite_in(d->sigma, 0.0, 1.0) && d->sigma > 0.0, "sigma");
  SYLVA__REQUIRE(d->leaf_age >= 1 && d->leaf_age <= 100000, "leaf_age");
  SYLVA__REQUIRE(finite_in(d->node_cost, 0.0, 1e6) && d->node_cost > 0.0, "node_cost");
  SYLVA__REQUIRE(finite_in(d->apical_flow, 0.0, 1.0), "apical_flow");
  SYLVA__REQUIRE(d->apical_zone >= 0 && d->apical_zone <= 100000, "apical_zone");
  SYLVA__REQUIRE(finite_in(d->mu, 0.0, 1e3), "mu");
  SYLVA__REQUIRE(finite_in(d->gamma, 0.0, 1e3), "gamma");
  for (int i = 0; i < 3; i++) SYLVA__REQUIRE(finite_in(d->tropism[i], -1e3, 1e3), "tropism");
  SYLVA__REQUIRE(finite_in(d->theta, 0.0, 180.0), "theta");
  SYLVA__REQUIRE(finite_in(d->divergence, -360.0, 360.0), "divergence");
  SYLVA__REQUIRE(finite_in(d->b_min, 1.0, 1e3) && d->b_min > 1.0, "b_min");
  SYLVA__REQUIRE(finite_in(d->b_max, d->b_min, 1e3), "b_max");
  SYLVA__REQUIRE(d->pyramid_depth >= 1 && d->pyramid_depth <= 64, "pyramid_depth");
  SYLVA__REQUIRE(finite_in(d->shade_spread, 0.0, 4.0), "shade_spread");
  SYLVA__REQUIRE(finite_in(d->shade_column, 0.0, 1.0), "shade_column");
  SYLVA__REQUIRE(finite_in(d->r_s, 0.0, 1e6), "r_s");
  SYLVA__REQUIRE(finite_in(d->r_tip, 0.0, 10.0) && d->r_tip > 0.0, "r_tip");
  SYLVA__REQUIRE(finite_in(d->pipe_exponent, 2.0, 3.5), "pipe_exponent");
  SYLVA__REQUIRE(d->m_min >= 0 && d->m_min <= d->m0 && d->m0 <= 1000, "markers");
  SYLVA__REQUIRE(finite_in(d->cone_angle, 0.0, 180.0) && d->cone_angle > 0.0, "markers");
  SYLVA__REQUIRE(finite_in(d->cone_radius, 0.0, 1e3) && d->cone_radius > 0.0, "markers");
  SYLVA__REQUIRE(d->initial_nodes >= 1 && d->initial_nodes <= 1000, "initial_nodes");
#undef SYLVA__REQUIRE
  return SYLVA_OK;
}
