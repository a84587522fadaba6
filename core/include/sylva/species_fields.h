/* sylva: the scalar fields of sylva_species_def in one list.
 *
 * SYLVA_SPECIES_FIELDS(X) calls X(name, type, default, min, max, bounds, group, snapshot)
 * once per field:
 *
 *   name      the member of sylva_species_def, also its scenario key
 *   type      double or int, the member's type
 *   default   the value of sylva_default_species_def()
 *   min, max  the range sylva_species_check() and the scenario parser accept
 *   bounds    SYLVA_FIELD_CLOSED [min, max], SYLVA_FIELD_MIN_EXCLUSIVE (min, max],
 *             SYLVA_FIELD_MAX_EXCLUSIVE [min, max) or SYLVA_FIELD_OPEN (min, max)
 *   group     species: a key of the scenario's species object; markers: a key of
 *             its "markers" object (sylva_species_check() names it "markers")
 *   snapshot  the field's place in a snapshot's species record, written as its type
 *             (f64 or i32); format 4 has every double before every int
 *
 * Generated from the list: the defaults (core/src/params.c), the range checks
 * (sylva_species_check), the snapshot's species record (core/src/snapshot.c), and
 * the species keys, ranges and canonical JSON order of scenarios
 * (proto/src/scenario.c). The list's order is the order in which the scenario
 * parser checks the keys and writes them back; keep it.
 *
 * Not in the list, written by hand where they are used: the growth equation
 * (growth.kind and growth.p[3], whose parameters depend on the kind), the
 * allocation enum, the tropism vector (three doubles in [-1000, 1000]), and the
 * two rules between fields: b_max >= b_min and m_min <= m0. In a snapshot,
 * growth.kind and allocation come first as u32, growth.p[] takes places 1-3 and
 * tropism[] places 14-16.
 *
 * Places 37 to 42 (ref_rho, acclimation, years, nursery, shade_weight, lift) are
 * written only in images with the SCALED flag (a species with a time scale or metric
 * counts), places 43 and 44 (crown_max, crown_max_exp) only in images with the CROWN
 * flag, places 45 to 47 (leaf_size, leaf_density, leaf_colour) only in images with
 * the FOLIAGE flag (a species whose foliage is not the default), place 48 (heartwood)
 * only in images with the WOOD flag, place 49 (lateral_reach) only in images with the
 * REACH flag, places 50 to 57 (wood_density and the biomass allometry) only in images
 * with the CARBON flag, places 58 to 64 (the stand's: stock_spread to snag_years) only
 * in images with the STAND flag, so images of worlds without such species keep their bytes. The foliage
 * changes no growth: it is what the leaf-bearing nodes carry (leaf_area, pictures,
 * glTF).
 *
 * Adding a field: add it to sylva_species_def and here (at the end of its group,
 * with the next place), raise SYLVA_SPECIES_SNAPSHOT_FIELDS, and document its key in
 * docs/scenario.md. Its place is written under a new header flag that implies the
 * others (core/src/snapshot.c), so older images keep their bytes and
 * SYLVA_SNAPSHOT_VERSION stays; without such a flag, raise the version. */
#ifndef SYLVA_SPECIES_FIELDS_H
#define SYLVA_SPECIES_FIELDS_H

#define SYLVA_FIELD_CLOSED 0
#define SYLVA_FIELD_MIN_EXCLUSIVE 1
#define SYLVA_FIELD_MAX_EXCLUSIVE 2
#define SYLVA_FIELD_OPEN (SYLVA_FIELD_MIN_EXCLUSIVE | SYLVA_FIELD_MAX_EXCLUSIVE)

/* clang-format off */
#define SYLVA_SPECIES_FIELDS(X)                                                                  \
  X(rho,           double, 0.1,   1e-4, 100,    SYLVA_FIELD_CLOSED,        species, 0)           \
  X(sprout_light,  double, 0.5,   0,    1,      SYLVA_FIELD_CLOSED,        species, 4)           \
  X(lambda,        double, 0.52,  0,    1,      SYLVA_FIELD_OPEN,          species, 5)           \
  X(k,             double, 0.5,   0,    1,      SYLVA_FIELD_CLOSED,        species, 6)           \
  X(w1,            double, 1.0,   0,    1e6,    SYLVA_FIELD_CLOSED,        species, 7)           \
  X(w2,            double, 0.6,   0,    1e6,    SYLVA_FIELD_CLOSED,        species, 8)           \
  X(w3,            double, 0.3,   0,    1e6,    SYLVA_FIELD_CLOSED,        species, 9)           \
  X(tau,           int,    6,     0,    100000, SYLVA_FIELD_CLOSED,        species, 30)          \
  X(alpha,         double, 4.0,   0,    1e6,    SYLVA_FIELD_MIN_EXCLUSIVE, species, 10)          \
  X(leaf_age,      int,    3,     1,    100000, SYLVA_FIELD_CLOSED,        species, 35)          \
  X(node_cost,     double, 1.0,   0,    1e6,    SYLVA_FIELD_MIN_EXCLUSIVE, species, 26)          \
  X(apical_flow,   double, 0.02,  0,    1,      SYLVA_FIELD_CLOSED,        species, 29)          \
  X(apical_zone,   int,    12,    0,    100000, SYLVA_FIELD_CLOSED,        species, 36)          \
  X(sigma,         double, 0.5,   0,    1,      SYLVA_FIELD_MIN_EXCLUSIVE, species, 11)          \
  X(mu,            double, 1.5,   0,    1000,   SYLVA_FIELD_CLOSED,        species, 12)          \
  X(gamma,         double, 0.5,   0,    1000,   SYLVA_FIELD_CLOSED,        species, 13)          \
  X(theta,         double, 45.0,  0,    180,    SYLVA_FIELD_CLOSED,        species, 17)          \
  X(divergence,    double, 137.5, -360, 360,    SYLVA_FIELD_CLOSED,        species, 18)          \
  X(b_min,         double, 1.8,   1,    1000,   SYLVA_FIELD_MIN_EXCLUSIVE, species, 19)          \
  X(b_max,         double, 2.2,   1,    1000,   SYLVA_FIELD_MIN_EXCLUSIVE, species, 20)          \
  X(pyramid_depth, int,    20,    1,    64,     SYLVA_FIELD_CLOSED,        species, 31)          \
  X(shade_spread,  double, 0.75,  0,    4,      SYLVA_FIELD_CLOSED,        species, 27)          \
  X(shade_column,  double, 0.002, 0,    1,      SYLVA_FIELD_CLOSED,        species, 28)          \
  X(r_s,           double, 0.35,  0,    1e6,    SYLVA_FIELD_CLOSED,        species, 21)          \
  X(r_tip,         double, 0.012, 0,    10,     SYLVA_FIELD_MIN_EXCLUSIVE, species, 22)          \
  X(pipe_exponent, double, 2.5,   2,    3.5,    SYLVA_FIELD_CLOSED,        species, 23)          \
  X(initial_nodes, int,    2,     1,    1000,   SYLVA_FIELD_CLOSED,        species, 34)          \
  X(years,         int,    0,     0,    1,      SYLVA_FIELD_CLOSED,        species, 39)          \
  X(nursery,       int,    0,     0,    200,    SYLVA_FIELD_CLOSED,        species, 40)          \
  X(ref_rho,       double, 0,     0,    100,    SYLVA_FIELD_CLOSED,        species, 37)          \
  X(acclimation,   double, 0,     0,    1,      SYLVA_FIELD_CLOSED,        species, 38)          \
  X(shade_weight,  double, 1,     0,    1000,   SYLVA_FIELD_MIN_EXCLUSIVE, species, 41)          \
  X(lift,          double, 0,     0,    0.9,    SYLVA_FIELD_CLOSED,        species, 42)          \
  X(crown_max,     double, 0,     0,    1000,   SYLVA_FIELD_CLOSED,        species, 43)          \
  X(crown_max_exp, double, 1,     0,    2,      SYLVA_FIELD_CLOSED,        species, 44)          \
  X(leaf_size,     double, 0.1,   0,    2,      SYLVA_FIELD_MIN_EXCLUSIVE, species, 45)          \
  X(leaf_density,  int,    6,     0,    1000,   SYLVA_FIELD_CLOSED,        species, 46)          \
  X(leaf_colour,   int,    0x4a7f35, 0, 0xffffff, SYLVA_FIELD_CLOSED,      species, 47)          \
  X(heartwood,     double, 0,     0,    1,      SYLVA_FIELD_CLOSED,        species, 48)          \
  X(lateral_reach, double, 1,     1,    4,      SYLVA_FIELD_CLOSED,        species, 49)          \
  X(wood_density,  double, 0,     0,    2000,   SYLVA_FIELD_CLOSED,        species, 50)          \
  X(biomass_form,  int,    0,     0,    3,      SYLVA_FIELD_CLOSED,        species, 51)          \
  X(biomass_a,     double, 0,     0,    1000,   SYLVA_FIELD_CLOSED,        species, 52)          \
  X(biomass_b,     double, 0,     -10,  10,     SYLVA_FIELD_CLOSED,        species, 53)          \
  X(biomass_c,     double, 0,     -10,  10,     SYLVA_FIELD_CLOSED,        species, 54)          \
  X(biomass_p,     double, 0,     -100, 100,    SYLVA_FIELD_CLOSED,        species, 55)          \
  X(biomass_q,     double, 0,     -100, 100,    SYLVA_FIELD_CLOSED,        species, 56)          \
  X(biomass_factor, double, 1,    0,    1,      SYLVA_FIELD_MIN_EXCLUSIVE, species, 57)          \
  X(stock_spread,  double, 0,     0,    1,      SYLVA_FIELD_CLOSED,        species, 58)          \
  X(vigour_spread, double, 0,     0,    2,      SYLVA_FIELD_CLOSED,        species, 59)          \
  X(height_light,  double, 0,     0,    1000,   SYLVA_FIELD_CLOSED,        species, 60)          \
  X(mortality_light, double, 0,   0,    1,      SYLVA_FIELD_CLOSED,        species, 61)          \
  X(mortality_years, int,  5,     1,    1000,   SYLVA_FIELD_CLOSED,        species, 62)          \
  X(mortality,     double, 0,     0,    1,      SYLVA_FIELD_CLOSED,        species, 63)          \
  X(snag_years,    int,    5,     0,    1000,   SYLVA_FIELD_CLOSED,        species, 64)          \
  X(m0,            int,    20,    0,    1000,   SYLVA_FIELD_CLOSED,        markers, 32)          \
  X(m_min,         int,    4,     0,    1000,   SYLVA_FIELD_CLOSED,        markers, 33)          \
  X(cone_angle,    double, 60.0,  0,    180,    SYLVA_FIELD_MIN_EXCLUSIVE, markers, 24)          \
  X(cone_radius,   double, 4.0,   0,    1000,   SYLVA_FIELD_MIN_EXCLUSIVE, markers, 25)
/* clang-format on */

/** Places in a snapshot's species record: the list's fields and the hand-written
 *  growth.p[3] and tropism[3]. */
#define SYLVA_SPECIES_SNAPSHOT_FIELDS 65

#endif
