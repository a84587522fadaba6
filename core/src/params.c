#include "sylva/params.h"

#include <math.h>

#include "sylva/species_fields.h"
#include "sylva/status.h"

/* Each listed field has the type the list gives it. */
#define SYLVA__TYPE_MATCHES(name, type, def, lo, hi, bounds, group, snap)                 \
  _Static_assert(_Generic(((sylva_species_def *)0)->name, type: 1, default: 0),           \
                 #name " is not a " #type " in sylva_species_def");
SYLVA_SPECIES_FIELDS(SYLVA__TYPE_MATCHES)
#undef SYLVA__TYPE_MATCHES

sylva_species_def sylva_default_species_def(void) {
  sylva_species_def d = {
#define SYLVA__DEFAULT(name, type, def, lo, hi, bounds, group, snap) .name = def,
      SYLVA_SPECIES_FIELDS(SYLVA__DEFAULT)
#undef SYLVA__DEFAULT
      .growth = {SYLVA_EQ_LOGISTIC, {2.0, 100.0, 0.34}},
      .allocation = SYLVA_ALLOC_LGTM,
      .tropism = {0.0, 0.0, 1.0},
  };
  return d;
}

static bool finite_in(double v, double lo, double hi) { return isfinite(v) && v >= lo && v <= hi; }

/* v within [lo, hi], either end left out as bounds says. */
static bool in_bounds(double v, double lo, double hi, int bounds) {
  if (!finite_in(v, lo, hi)) return false;
  if ((bounds & SYLVA_FIELD_MIN_EXCLUSIVE) && v == lo) return false;
  if ((bounds & SYLVA_FIELD_MAX_EXCLUSIVE) && v == hi) return false;
  return true;
}

/* The name a failed check reports: the key, or "markers" for the marker keys. */
#define SYLVA__CHECK_NAME_species(name) #name
#define SYLVA__CHECK_NAME_markers(name) "markers"

int sylva_species_check(const sylva_species_def *d, const char **field) {
#define SYLVA__REQUIRE(cond, name)                                                         \
  do {                                                                                     \
    if (!(cond)) {                                                                         \
      if (field) *field = name;                                                            \
      return SYLVA_ERANGE;                                                                 \
    }                                                                                      \
  } while (0)
#define SYLVA__RANGE(name, type, def, lo, hi, bounds, group, snap) \
  SYLVA__REQUIRE(in_bounds((double)d->name, lo, hi, bounds), SYLVA__CHECK_NAME_##group(name));
  SYLVA_SPECIES_FIELDS(SYLVA__RANGE)
#undef SYLVA__RANGE
  /* What the list does not hold (sylva/species_fields.h). */
  SYLVA__REQUIRE(d->b_max >= d->b_min, "b_max");
  SYLVA__REQUIRE(d->m_min <= d->m0, "markers");
  SYLVA__REQUIRE(d->biomass_form != 1 || d->wood_density > 0, "wood_density");
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
  for (int i = 0; i < 3; i++) SYLVA__REQUIRE(finite_in(d->tropism[i], -1e3, 1e3), "tropism");
#undef SYLVA__REQUIRE
  return SYLVA_OK;
}
