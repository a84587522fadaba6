/* Every formula of docs/model.md against hand-worked values: growth equations and their
 * derivatives, the cap/stop rule, BH shares, priority weights, light sensitivity,
 * lateral directions, the generator, and one hand-worked allocation. */
#include <string.h>

#include "../check.h"
#include "allocate.h"
#include "light.h"
#include "rng.h"
#include "shoot.h"
#include "sort.h"
#include "sylva/sylva.h"
#include "world_impl.h"

/* Allocation at iteration T of a world set up by hand: every stem's clock (its time on
 * its growth equation, docs/model.md "Stands") where a stem that grew each season up
 * to T - 1 has it, as sylva_world_step would have left it. */
static int allocate_at(sylva_world *w, int T) {
  for (int k = 0; k < w->stem_count; k++) {
    w->stems[k].clock = (double)(T - 1 - w->stems[k].born);
    w->stems[k].clock_prev = w->stems[k].clock - 1.0;
  }
  return sylva__allocate(w, T);
}

static void test_derivatives(void) {
  sylva_equation eqs[] = {
      {SYLVA_EQ_LOGISTIC, {2.0, 100.0, 0.34}},
      {SYLVA_EQ_BERTALANFFY, {90.0, 0.12, 0.0}},
      {SYLVA_EQ_WEIBULL, {80.0, 0.01, 2.2}},
      {SYLVA_EQ_WEIBULL, {80.0, 0.2, 0.8}},
      {SYLVA_EQ_GOMPERTZ, {100.0, 4.0, 0.25}},
  };
  for (size_t e = 0; e < sizeof eqs / sizeof eqs[0]; e++) {
    for (double t = 0.5; t < 40.0; t += 0.75) {
      double h = 1e-5;
      double fd = (sylva_equation_value(&eqs[e], t + h) - sylva_equation_value(&eqs[e], t - h)) /
                  (2 * h);
      double an = sylva_equation_rate(&eqs[e], t);
      CHECK_NEAR(an, fd, 1e-6 * (1.0 + fabs(an)));
    }
  }
  /* hand-worked values of the logistic default: X(0) = X0, dX/dt(0) = 100*0.34*49/50^2 */
  CHECK_NEAR(sylva_equation_value(&eqs[0], 0.0), 2.0, 1e-12);
  CHECK_NEAR(sylva_equation_rate(&eqs[0], 0.0), 0.6664, 1e-12);
  CHECK_NEAR(sylva_equation_limit(&eqs[0]), 100.0, 0.0);
  CHECK_NEAR(sylva_equation_limit(&eqs[1]), 90.0, 0.0);
  CHECK_NEAR(sylva_equation_value(&eqs[1], 0.0), 0.0, 0.0);
}

static void test_cap_and_stop(void) {
  sylva_equation lg = {SYLVA_EQ_LOGISTIC, {2.0, 100.0, 0.34}};
  /* c(T) = round(X'(T - 1)): worked by hand from X' (docs/model.md, "Cap") */
  int expect[] = {0, 1, 1, 1, 2, 2, 3, 4, 5, 6, 7, 8, 8, 8, 8, 7, 6, 5, 4, 3, 2, 2, 1, 1, 1, 0, 0};
  for (int T = 1; T <= 26; T++) CHECK_INT(sylva_equation_cap(&lg, T), expect[T]);
  /* finished at the first T past the inflection whose rate is below one internode
   * (docs/model.md, "Stop"): X'(21) = 1.2238, X'(22) = 0.8902, so T = 23 */
  CHECK_NEAR(sylva_equation_rate(&lg, 21.0), 1.2238, 1e-4);
  CHECK_NEAR(sylva_equation_rate(&lg, 22.0), 0.8902, 1e-4);
  for (int T = 1; T <= 22; T++) CHECK(!sylva_equation_stops(&lg, T));
  CHECK(sylva_equation_stops(&lg, 23));
  CHECK(sylva_equation_decreasing(&lg, 20));
  CHECK(!sylva_equation_decreasing(&lg, 5));
  /* round half up: Weibull with omega3 = 1 has X'(0) = omega1 * omega2 = 2.5 */
  sylva_equation half = {SYLVA_EQ_WEIBULL, {5.0, 0.5, 1.0}};
  CHECK_INT(sylva_equation_cap(&half, 1), 3);
  /* a rate that starts at 0 (Weibull omega3 > 1) does not grow yet, is not finished */
  sylva_equation late = {SYLVA_EQ_WEIBULL, {80.0, 0.01, 2.2}};
  CHECK_INT(sylva_equation_cap(&late, 1), 0);
  CHECK(!sylva_equation_stops(&late, 1));
  CHECK(!sylva_equation_stops(&late, 2));
  int first_growth = 0;
  for (int T = 1; T < 100 && !first_growth; T++)
    if (sylva_equation_cap(&late, T) > 0) first_growth = T;
  CHECK(first_growth >= 2);
  int stop = 0;
  for (int T = 1; T < 400 && !stop; T++)
    if (sylva_equation_stops(&late, T)) stop = T;
  CHECK(stop > first_growth);
}

static void test_bh_and_priority(void) {
  /* (Lm + Ll)(1 - l) Ll / (l Lm + (1 - l) Ll) */
  CHECK_NEAR(sylva__bh_share(3.0, 1.0, 0.5), 1.0, 1e-15);
  CHECK_NEAR(sylva__bh_share(3.0, 1.0, 0.52), 1.92 / 2.04, 1e-15);
  CHECK_NEAR(sylva__bh_share(0.0, 2.0, 0.52), 2.0, 1e-15); /* apex: its own light */
  CHECK_NEAR(sylva__bh_share(0.0, 0.0, 0.52), 0.0, 0.0);   /* 0 denominator */
  /* excurrent lambda gives laterals less than decurrent */
  CHECK(sylva__bh_share(5.0, 1.0, 0.6) < sylva__bh_share(5.0, 1.0, 0.4));
  /* w(r): w1 below k, then linear w2 -> w3 over [k, 1) */
  CHECK_NEAR(sylva__priority_weight(0, 10, 0.5, 1.0, 0.6, 0.3), 1.0, 0.0);
  CHECK_NEAR(sylva__priority_weight(4, 10, 0.5, 1.0, 0.6, 0.3), 1.0, 0.0);
  CHECK_NEAR(sylva__priority_weight(5, 10, 0.5, 1.0, 0.6, 0.3), 0.6, 1e-15);
  CHECK_NEAR(sylva__priority_weight(7, 10, 0.5, 1.0, 0.6, 0.3), 0.48, 1e-15);
  CHECK_NEAR(sylva__priority_weight(9, 10, 0.5, 1.0, 0.6, 0.3), 0.36, 1e-15);
  CHECK_NEAR(sylva__priority_weight(9, 10, 1.0, 1.0, 0.6, 0.3), 1.0, 0.0);
  CHECK_NEAR(sylva__priority_weight(0, 4, 0.0, 1.0, 0.6, 0.3), 0.6, 1e-15);
}

static void test_light_sensitivity(void) {
  /* L = alpha * l ^ (age ^ sigma) */
  CHECK_NEAR(sylva__collected(4.0, 0.25, pow(4.0, 0.5)), 0.25, 1e-15);
  CHECK_NEAR(sylva__collected(4.0, 0.25, pow(1.0, 0.5)), 1.0, 1e-15);
  CHECK_NEAR(sylva__collected(6.0, 0.5, pow(9.0, 1.0)), 6.0 / 512.0, 1e-15);
  CHECK_NEAR(sylva__collected(4.0, 0.0, 1.0), 0.0, 0.0);
  CHECK_NEAR(sylva__collected(4.0, 1.0, 3.0), 4.0, 0.0);
  CHECK_NEAR(sylva__collected(4.0, 0.3, 0.0), 4.0, 0.0); /* a newborn node */
  /* a lower sigma makes old nodes less sensitive to shade */
  CHECK(sylva__collected(4.0, 0.5, pow(9.0, 0.5)) > sylva__collected(4.0, 0.5, pow(9.0, 1.0)));
}

static void test_lateral_direction(void) {
  double up[3] = {0, 0, 1}, out[3];
  sylva__lateral_direction(up, 45.0, 0.0, out);
  CHECK_NEAR(out[2], cos(45.0 * 3.14159265358979323846 / 180.0), 1e-12);
  CHECK_NEAR(out[0] * out[0] + out[1] * out[1] + out[2] * out[2], 1.0, 1e-12);
  /* phyllotaxis: the divergence turns the lateral around the axis */
  double a[3], b[3];
  sylva__lateral_direction(up, 45.0, 0.0, a);
  sylva__lateral_direction(up, 45.0, 137.5, b);
  double ang = acos((a[0] * b[0] + a[1] * b[1]) / (sqrt(a[0] * a[0] + a[1] * a[1]) *
                                                    sqrt(b[0] * b[0] + b[1] * b[1])));
  CHECK_NEAR(ang * 180.0 / 3.14159265358979323846, 137.5, 1e-9);
  double side[3] = {1, 0, 0};
  sylva__lateral_direction(side, 90.0, 30.0, out);
  CHECK_NEAR(out[0], 0.0, 1e-12);
}

typedef struct sort_item {
  int32_t key, tie;
  double pad[2];
} sort_item;

static int cmp_sort_item(const void *a, const void *b) {
  const sort_item *x = a, *y = b;
  if (x->key != y->key) return (x->key > y->key) - (x->key < y->key);
  return (x->tie > y->tie) - (x->tie < y->tie);
}

/* sylva__sort (the allocation's, on the pool's threads) gives qsort's order under a
 * total order: keys with many repeats, ties broken by a unique second key. */
static void test_sort(void) {
  sylva__rng r;
  sylva__rng_seed(&r, 7);
  static sort_item a[3000], b[3000];
  size_t sizes[] = {0, 1, 2, 3, 17, 256, 3000};
  for (int mode = 0; mode < 3; mode++) /* random keys, ascending, descending */
    for (size_t t = 0; t < sizeof sizes / sizeof *sizes; t++) {
      size_t n = sizes[t];
      for (size_t i = 0; i < n; i++) {
        int32_t key = mode == 0 ? (int32_t)sylva__rng_below(&r, 40)
                      : mode == 1 ? (int32_t)i : (int32_t)(n - i);
        a[i] = b[i] = (sort_item){key, (int32_t)(i % 7), {(double)i, 0.0}};
        if (mode == 0) a[i].tie = b[i].tie = (int32_t)i;
      }
      sylva__sort(a, n, sizeof *a, cmp_sort_item);
      if (n) qsort(b, n, sizeof *b, cmp_sort_item);
      CHECK(n == 0 || memcmp(a, b, n * sizeof *a) == 0);
    }
}

static void test_rng(void) {
  sylva__rng a, b, c;
  sylva__rng_seed(&a, 42);
  sylva__rng_seed(&b, 42);
  sylva__rng_seed(&c, 43);
  int same = 1, differ = 0;
  for (int i = 0; i < 1000; i++) {
    uint64_t x = sylva__rng_next(&a), y = sylva__rng_next(&b), z = sylva__rng_next(&c);
    same &= x == y;
    differ += x != z;
  }
  CHECK(same);
  CHECK(differ > 990);
  /* known first value pins the generator across builds */
  sylva__rng_seed(&a, 1);
  uint64_t first = sylva__rng_next(&a);
  sylva__rng_seed(&a, 1);
  CHECK(first == sylva__rng_next(&a));
  double sum = 0;
  for (int i = 0; i < 100000; i++) {
    double u = sylva__rng_unit(&a);
    CHECK(u >= 0.0 && u < 1.0 ? 1 : 0);
    sum += u;
  }
  CHECK_NEAR(sum / 100000, 0.5, 0.01);
  int counts[7] = {0};
  for (int i = 0; i < 70000; i++) counts[sylva__rng_below(&a, 7)]++;
  for (int i = 0; i < 7; i++) CHECK_NEAR(counts[i], 10000, 500);
  int32_t perm[50];
  sylva__rng_permutation(&a, perm, 50);
  int seen[50] = {0};
  for (int i = 0; i < 50; i++) seen[perm[i]]++;
  int ok = 1;
  for (int i = 0; i < 50; i++) ok &= seen[i] == 1;
  CHECK(ok);
}

/* The hand-worked allocations on a trunk a-b-c (apex c) with no laterals. */

/* Sets the light of a, b, c and the flows Q of the root, a, b, c. */
static void set_flows(sylva_world *w, const double light[3], const double q[4]) {
  for (int i = 0; i < 3; i++) w->light[i + 1] = light[i];
  for (int i = 0; i < 4; i++) w->q[i] = q[i];
}

/* The trunk: lambda 0.5, tau 0, every bud free to sprout (the apical zone has its
 * own test); L = 1, 2, 4 and Q = 7, 6, 4 at a, b, c, and R_trunk 10. */
static sylva_world *trunk(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_species_def sp = sylva_default_species_def();
  sp.lambda = 0.5;
  sp.tau = 0;
  sp.initial_nodes = 3;
  sp.apical_zone = 0;
  int s = sylva_world_add_species(w, &sp, "x");
  double root[1][3] = {{0, 0, 0}};
  sylva_plant_def pd = {s, "t", (const double(*)[3])root, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &pd, NULL), 0);
  CHECK_INT(sylva__reserve_scratch(w), 0);
  CHECK_INT(w->nodes.count, 4);
  set_flows(w, (const double[]){1, 2, 4}, (const double[]){10, 7, 6, 4});
  return w;
}

/* Sprout i of the last allocation: its slot, R and internodes. */
static void check_sprout(const sylva_world *w, size_t i, int32_t slot, double r, int32_t n) {
  if (i >= w->sprouts.len) return;
  CHECK_INT(w->sprouts.data[i].slot, slot);
  CHECK_NEAR(w->sprouts.data[i].r, r, 1e-12);
  CHECK_INT(w->sprouts.data[i].n, n);
}

/* The hand-worked allocation: the apex grows 6, b sprouts a lateral of 3, a nothing. */
static void test_allocation_hand_worked(void) {
  /* L = 1, 2, 4 -> Q = 7, 6, 4; R_trunk = 10; lambda 0.5, k 0.5, tau 0.
   * RBH: a = 7*.5*1/3.5 = 1, b = 6*.5*2/3 = 2, c = 4*.5*4/2 = 4; ranks c, b, a;
   * w = 1, 1, 0.6 - 0.3 * (2/3 - 1/2) / (1/2) = 0.5 -> weighted 4, 2, 0.5 (sum 6.5);
   * R = 6.15, 3.08, 0.77. */
  sylva_world *w = trunk();
  CHECK_INT(allocate_at(w, 12), 0); /* c(12) = 8 */
  CHECK_INT(w->sprouts.len, 2);
  if (w->sprouts.len == 2) {
    CHECK(w->sprouts.data[0].apex);
    check_sprout(w, 0, 3, 10.0 * 4.0 / 6.5, 6);
    CHECK(!w->sprouts.data[1].apex);
    check_sprout(w, 1, 2, 10.0 * 2.0 / 6.5, 3);
  }
  sylva_world_destroy(w);
}

/* The cap limits a rich shoot: c(3) = 1. */
static void test_allocation_cap(void) {
  sylva_world *w = trunk();
  CHECK_INT(allocate_at(w, 3), 0);
  CHECK_INT(w->sprouts.len, 2);
  if (w->sprouts.len) CHECK_INT(w->sprouts.data[0].n, 1);
  sylva_world_destroy(w);
}

/* The laterals' reach (docs/model.md, "Species in years"): a shoot on an axis other
 * than the trunk grows up to round(f X(T)) - round(f X(T-1)) internodes, f graded by
 * its node's depth below the stem's top, 1 + (lateral_reach - 1) min(1, depth / crown
 * height). With ref_rho and the logistic X0 2, Xm 60, r 0.3: X(2) = 3.547, X(3) =
 * 4.692. The leader's cap at T = 3 is round(4.692) - round(3.547) = 5 - 4 = 1. The
 * stem 1 m tall with a crown 0.8 m high; a one-node lateral d on b, with resources to
 * spare. d at z 0.2 (0.8 below the top: the full reach): reach 2, round(9.384) -
 * round(7.094) = 9 - 7 = 2; reach 3, round(14.08) - round(10.64) = 14 - 11 = 3. d at
 * z 0.6 (half the crown below the top) with reach 3: f = 2, 2 internodes; at z 1.1
 * (above the top): f = 1, 1. The apex grows 1 in every case. */
static void test_allocation_lateral_reach(void) {
  const struct {
    double reach, z;
    int32_t n;
  } cases[] = {{1.0, 0.2, 1}, {2.0, 0.2, 2}, {3.0, 0.2, 3}, {3.0, 0.6, 2}, {3.0, 1.1, 1}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    sylva_world *w = trunk();
    sylva_species_def *d = &w->species[0].def;
    d->ref_rho = d->rho;
    d->growth = (sylva_equation){SYLVA_EQ_LOGISTIC, {2.0, 60.0, 0.3}};
    d->lateral_reach = cases[i].reach;
    w->stems[0].stats.height = 1.0;
    w->stems[0].stats.crown_height = 0.8;
    double pd[3] = {0.07, 0, cases[i].z};
    CHECK_INT(sylva__add_node(w, 2, true, pd, 0, 0), 4);
    CHECK_INT(sylva__reserve_scratch(w), 0);
    set_flows(w, (const double[]){1, 2, 4}, (const double[]){100, 15, 14, 4});
    w->light[4] = 4.0;
    w->q[4] = 4.0;
    CHECK_INT(allocate_at(w, 3), 0);
    int32_t apex = -1, lateral = -1;
    for (size_t k = 0; k < w->sprouts.len; k++) {
      if (w->sprouts.data[k].slot == 3) apex = w->sprouts.data[k].n;
      if (w->sprouts.data[k].slot == 4) lateral = w->sprouts.data[k].n;
    }
    CHECK_INT(apex, 1);
    CHECK_INT(lateral, cases[i].n);
    sylva_world_destroy(w);
  }
}

/* Apical control (T <= tau): the apex is ranked first even with the least light. */
static void test_allocation_apical_control(void) {
  sylva_world *w = trunk();
  w->species[0].def.tau = 20;
  set_flows(w, (const double[]){5, 5, 0.1}, (const double[]){100, 10.1, 5.1, 0.1});
  CHECK_INT(allocate_at(w, 12), 0);
  double apex_r = 0;
  for (size_t i = 0; i < w->sprouts.len; i++)
    if (w->sprouts.data[i].apex) apex_r = w->sprouts.data[i].r;
  /* RBH apex 0.1 w1; the others ranked 1, 2 of 3 */
  double rb_b = sylva__bh_share(0.1, 5, 0.5), rb_a = sylva__bh_share(5.1, 5, 0.5);
  double hi = rb_a > rb_b ? rb_a : rb_b, lo = rb_a > rb_b ? rb_b : rb_a;
  double sum = 0.1 * 1.0 + hi * 1.0 + lo * 0.5;
  CHECK_NEAR(apex_r, 100.0 * 0.1 / sum, 1e-12);
  sylva_world_destroy(w);
}

/* The apex's share of the main flow (docs/model.md, "Allocation"): apical_flow 0.5. */
static void test_allocation_apical_flow(void) {
  /* lambda 0.6, no apical control: L = 1, 2, 4, Q = 7, 6, 4. RBH a = 7*.4*1/(3.6+.4)
   * = 0.7, b = 6*.4*2/(2.4+.8) = 1.5, apex own 4; the rest 7 - 0.7 - 1.5 - 4 = 0.8.
   * apical_flow 0.5: RBH apex 4.4; ranks apex, b, a with w 1, 1, 0.5: weighted
   * 4.4, 1.5, 0.35 (sum 6.25), R_trunk 10 -> apex 7.04 (7 internodes), b 2.4 (2). */
  sylva_world *w = trunk();
  w->species[0].def.lambda = 0.6;
  w->species[0].def.apical_flow = 0.5;
  CHECK_INT(allocate_at(w, 12), 0);
  CHECK_INT(w->sprouts.len, 2);
  if (w->sprouts.len == 2) {
    CHECK(w->sprouts.data[0].apex);
    CHECK_NEAR(w->sprouts.data[0].r, 10.0 * 4.4 / 6.25, 1e-12);
    CHECK_INT(w->sprouts.data[0].n, 7);
    CHECK_NEAR(w->sprouts.data[1].r, 10.0 * 1.5 / 6.25, 1e-12);
    CHECK_INT(w->sprouts.data[1].n, 2);
  }
  sylva_world_destroy(w);
}

/* apical_flow 0: the apex has its own light only (4 of 5.85). */
static void test_allocation_no_apical_flow(void) {
  sylva_world *w = trunk();
  w->species[0].def.lambda = 0.6;
  w->species[0].def.apical_flow = 0.0;
  CHECK_INT(allocate_at(w, 12), 0);
  if (w->sprouts.len) CHECK_NEAR(w->sprouts.data[0].r, 10.0 * 4.0 / 5.85, 1e-12);
  sylva_world_destroy(w);
}

/* lambda 0.5 leaves no rest: apical_flow changes nothing. */
static void test_allocation_no_rest(void) {
  sylva_world *w = trunk();
  w->species[0].def.apical_flow = 1.0;
  CHECK_INT(allocate_at(w, 12), 0);
  if (w->sprouts.len) CHECK_NEAR(w->sprouts.data[0].r, 10.0 * 4.0 / 6.5, 1e-12);
  sylva_world_destroy(w);
}

/* The apical zone (docs/model.md, "Allocation"): lateral buds within it stay dormant. */
static void test_allocation_apical_zone(void) {
  /* The first case again (lambda 0.5, RBH a 1, b 2, apex 4). Zone 1: b is 1 internode
   * below the apex and a 2, both may sprout: as before. Zone 2: b's bud is dormant
   * (RBH 0); ranks apex, a, b with w 1, 1, 0.5: weighted 4, 1, 0 (sum 5) -> apex 8
   * (cap 8), a 2 (2 internodes). Zone 3: a too; the apex takes all 10 and grows its
   * cap of 8. */
  /* zone; then the expected sprouts in order: slot, R, internodes */
  const struct {
    int zone;
    size_t len;
    int32_t slot[2];
    double r[2];
    int32_t n[2];
  } zones[] = {
      {1, 2, {3, 2}, {10.0 * 4.0 / 6.5, 10.0 * 2.0 / 6.5}, {6, 3}},
      {2, 2, {3, 1}, {8.0, 2.0}, {8, 2}},
      {3, 1, {3, -1}, {10.0, 0.0}, {8, 0}},
  };
  sylva_world *w = trunk();
  w->species[0].def.apical_flow = 0.0;
  for (size_t z = 0; z < sizeof zones / sizeof zones[0]; z++) {
    w->species[0].def.apical_zone = zones[z].zone;
    CHECK_INT(allocate_at(w, 12), 0);
    CHECK_INT(w->sprouts.len, zones[z].len);
    for (size_t i = 0; i < zones[z].len; i++)
      check_sprout(w, i, zones[z].slot[i], zones[z].r[i], zones[z].n[i]);
  }
  sylva_world_destroy(w);
}

/* b = b_min while T <= tau, then linear to b_max at the first T with X(T) >= 0.95 limit. */
static void test_shade_base(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_species_def sp = sylva_default_species_def(); /* tau 6, b 1.8 .. 2.2 */
  CHECK(sylva_world_add_species(w, &sp, "x") == 0);
  sylva__species *s = &w->species[0];
  /* X(T) = 100 / (1 + 49 e^(-0.34 T)): X(20) = 94.82, X(21) = 96.27, so T95 = 21 */
  CHECK_INT(s->t95, 21);
  CHECK_NEAR(sylva__species_b(s, 0), 1.8, 0.0);
  CHECK_NEAR(sylva__species_b(s, 6), 1.8, 0.0);
  CHECK_NEAR(sylva__species_b(s, 7), 1.8 + 0.4 / 15.0, 1e-15);
  CHECK_NEAR(sylva__species_b(s, 13), 1.8 + 0.4 * 7.0 / 15.0, 1e-15);
  CHECK_NEAR(sylva__species_b(s, 20), 1.8 + 0.4 * 14.0 / 15.0, 1e-15);
  CHECK_NEAR(sylva__species_b(s, 21), 2.2, 0.0);
  CHECK_NEAR(sylva__species_b(s, 60), 2.2, 0.0);
  /* the fixed-point pyramid weights are b^-q in units of 2^-32, rounded */
  double b = 1.8 + 0.4 * 7.0 / 15.0;
  const sylva__pyramid *shade = sylva__species_shade(s, 13);
  const int64_t *wt = shade->w;
  CHECK_INT(shade->depth, 20);
  CHECK_INT(wt[0], (int64_t)floor(SYLVA__SHADE_ONE / b + 0.5));
  CHECK_INT(wt[2], (int64_t)floor(SYLVA__SHADE_ONE / (b * b * b) + 0.5));
  CHECK_INT(wt[19], (int64_t)floor(pow(b, -20.0) * SYLVA__SHADE_ONE + 0.5));
  /* half-width floor(q * shade_spread): 0.75 by default, so the base is 31 voxels wide */
  CHECK_INT(shade->half[0], 0);
  CHECK_INT(shade->half[1], 1);
  CHECK_INT(shade->half[3], 3);
  CHECK_INT(shade->half[19], 15);
  CHECK_INT(shade->column, (int64_t)floor(0.002 * SYLVA__SHADE_ONE + 0.5));
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(derivatives), CHECK_TEST(cap_and_stop), CHECK_TEST(bh_and_priority),
      CHECK_TEST(light_sensitivity), CHECK_TEST(lateral_direction), CHECK_TEST(rng), CHECK_TEST(sort),
      CHECK_TEST(allocation_hand_worked), CHECK_TEST(allocation_cap),
      CHECK_TEST(allocation_lateral_reach),
      CHECK_TEST(allocation_apical_control), CHECK_TEST(allocation_apical_flow),
      CHECK_TEST(allocation_no_apical_flow), CHECK_TEST(allocation_no_rest),
      CHECK_TEST(allocation_apical_zone), CHECK_TEST(shade_base)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("formulas");
}
