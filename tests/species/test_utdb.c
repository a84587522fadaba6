/* The Urban Tree Database library (server/species/utdb.c): the built-in tables, the
 * README's check values, each equation form, clamping, the species a growing tree
 * can use, and bad input. */
#include "utdb.h"

#include <stdint.h>

#include "../check.h"

/* The embedded tables (embed.py), for the damaged-input tests. */
extern const char sylva__utdb_ts6[];
extern const size_t sylva__utdb_ts6_len;
extern const char sylva__utdb_ts2[];
extern const size_t sylva__utdb_ts2_len;

static sylva_utdb *builtin(void) {
  sylva_utdb *u = NULL;
  int rc = sylva_utdb_builtin(&u);
  CHECK_INT(rc, SYLVA_OK);
  if (!u) {
    fprintf(stderr, "the built-in tables do not parse\n");
    exit(1);
  }
  return u;
}

static const sylva_utdb_species *must_find(const sylva_utdb *u, const char *region,
                                           const char *code) {
  const sylva_utdb_species *s = sylva_utdb_find(u, region, code);
  if (!s) {
    fprintf(stderr, "no species %s %s\n", region, code);
    exit(1);
  }
  return s;
}

/* Species per region: TS6 holds 350 (region, code) pairs in 17 regions. */
static void test_builtin_counts(void) {
  static const struct {
    const char *region;
    int count;
  } regions[] = {{"CenFla", 20}, {"GulfCo", 19}, {"InlEmp", 22}, {"InlVal", 23},
                 {"InterW", 21}, {"LoMidW", 20}, {"MidWst", 17}, {"NMtnPr", 20},
                 {"NoCalC", 21}, {"NoEast", 21}, {"PacfNW", 22}, {"Piedmt", 21},
                 {"SacVal", 20}, {"SoCalC", 20}, {"SWDsrt", 22}, {"TpIntW", 20},
                 {"Tropic", 21}};
  sylva_utdb *u = builtin();
  CHECK_INT(sylva_utdb_count(u), 350);
  int total = 0;
  for (size_t r = 0; r < sizeof regions / sizeof regions[0]; r++) {
    int n = 0;
    for (int i = 0; i < sylva_utdb_count(u); i++)
      n += strcmp(sylva_utdb_at(u, i)->region, regions[r].region) == 0;
    if (n != regions[r].count) fprintf(stderr, "region %s\n", regions[r].region);
    CHECK_INT(n, regions[r].count);
    total += n;
  }
  CHECK_INT(total, 350);
  /* TS6's order, which is not strcmp's (SoCalC comes before SWDsrt). */
  CHECK(strcmp(sylva_utdb_at(u, 0)->code, "ACRU") == 0);
  CHECK(strcmp(sylva_utdb_at(u, 0)->region, "CenFla") == 0);
  CHECK(strcmp(sylva_utdb_at(u, 349)->code, "VEME") == 0);
  CHECK(sylva_utdb_at(u, 350) == NULL);
  CHECK(sylva_utdb_at(u, -1) == NULL);
  CHECK(sylva_utdb_find(u, "NoEast", "plac") == NULL);
  CHECK(sylva_utdb_find(u, "noeast", "PLAC") == NULL);
  CHECK(sylva_utdb_find(u, "NoEast", "PLA") == NULL);

  /* Names from TS2, trimmed; a species TS2 lacks keeps TS6's scientific name. */
  const sylva_utdb_species *s = must_find(u, "NoEast", "PLAC");
  CHECK(strcmp(s->scientific, "Platanus x acerifolia") == 0);
  CHECK(strcmp(s->common, "London planetree") == 0);
  CHECK(strcmp(s->type, "BDL") == 0);
  CHECK(strcmp(must_find(u, "SacVal", "GIBI")->scientific, "Ginkgo biloba") == 0);
  CHECK(strcmp(must_find(u, "InlEmp", "BRPO")->scientific, "Brachychiton populneum") == 0);
  CHECK(strcmp(must_find(u, "TpIntW", "CR")->scientific, "Crataegus sp.") == 0);
  const sylva_utdb_species *waro = must_find(u, "InlVal", "WARO");
  CHECK(strcmp(waro->scientific, "Washingtonia robusta") == 0);
  CHECK(strcmp(waro->common, "") == 0);
  CHECK(!sylva_utdb_complete(waro));
  CHECK(!waro->curve[SYLVA_UTDB_DBH].present);
  CHECK(waro->curve[SYLVA_UTDB_HEIGHT].present);
  CHECK(isnan(waro->age_min) && isnan(waro->age_max));
  CHECK(strcmp(must_find(u, "InlVal", "FRVE_G")->scientific, "Fraxinus velutina 'Modesto'") == 0);

  /* Per curve: form, coefficients, counts and R², ranges. */
  const sylva_utdb_curve *c = &s->curve[SYLVA_UTDB_DBH];
  CHECK(strcmp(c->form, "quad") == 0);
  CHECK_NEAR(c->a, 2.40322, 0);
  CHECK_NEAR(c->c, -0.00705, 0);
  CHECK(isnan(c->mse));
  CHECK_INT(c->n, 49);
  CHECK_NEAR(c->r2, 0.889, 0);
  CHECK_NEAR(c->apps_min, 2.4, 0);
  CHECK_NEAR(c->apps_max, 61.76, 0);
  CHECK_NEAR(c->data_max, 164.6, 0);
  CHECK_INT(s->curve[SYLVA_UTDB_HEIGHT].n, 53);
  CHECK_NEAR(s->curve[SYLVA_UTDB_HEIGHT].r2, 0.892, 0);
  c = &s->curve[SYLVA_UTDB_CROWN_DIA];
  CHECK(strcmp(c->form, "loglogw1") == 0);
  CHECK_NEAR(c->mse, 0.01977, 0);
  CHECK_NEAR(c->c, 0.01977, 0);
  CHECK_NEAR(s->age_min, 0, 0);
  CHECK_NEAR(s->age_max, 92, 0);
  CHECK_NEAR(s->curve[SYLVA_UTDB_DBH].x_min, 0, 0);
  CHECK_NEAR(s->curve[SYLVA_UTDB_DBH].x_max, 92, 0);
  for (int m = SYLVA_UTDB_HEIGHT; m < SYLVA_UTDB_MEASURES; m++) {
    CHECK_NEAR(s->curve[m].x_min, 2.4, 0);
    CHECK_NEAR(s->curve[m].x_max, 61.76, 0);
  }
  /* An equation without n, R² or data range in the table. */
  c = &must_find(u, "GulfCo", "BUCA")->curve[SYLVA_UTDB_LEAF_AREA];
  CHECK(c->present);
  CHECK_INT(c->n, 0);
  CHECK(isnan(c->r2) && isnan(c->data_min) && isnan(c->data_max));
  /* Without an age -> dbh equation a dbh -> X one is held to dbh >= 0 only. */
  CHECK_NEAR(c->x_min, 0, 0);
  CHECK(isinf(c->x_max));

  /* Every species with an age -> dbh equation has the other three (334 of 350). */
  int complete = 0;
  for (int i = 0; i < sylva_utdb_count(u); i++) {
    const sylva_utdb_species *t = sylva_utdb_at(u, i);
    complete += sylva_utdb_complete(t);
    CHECK(sylva_utdb_complete(t) == t->curve[SYLVA_UTDB_DBH].present);
    CHECK(t->curve[SYLVA_UTDB_DBH].present == t->curve[SYLVA_UTDB_AGE].present);
  }
  CHECK_INT(complete, 334);
  sylva_utdb_free(u);
}

/* The README's check table: NoEast chained as published (loglogw1 inside form, no
 * clamping), dbh / height / crown diameter / crown height, printed to 0.1. */
static void test_check_values(void) {
  static const struct {
    const char *code;
    double age;
    double dbh, height, crown_dia, crown_ht;
  } rows[] = {
      {"PLAC", 10, 14.6, 7.5, 5.5, 4.9},   {"PLAC", 20, 25.5, 10.2, 8.3, 7.0},
      {"PLAC", 40, 42.9, 14.2, 11.8, 10.0}, {"TICO", 10, 15.9, 7.0, 4.9, 5.1},
      {"TICO", 20, 27.1, 9.5, 8.0, 7.1},   {"TICO", 40, 44.8, 13.1, 11.7, 9.9},
      {"GIBI", 10, 12.6, 6.6, 3.4, 4.2},   {"GIBI", 20, 22.6, 10.2, 5.5, 7.0},
      {"GIBI", 40, 40.8, 15.3, 8.9, 11.1}, {"QURU", 10, 12.0, 6.5, 4.3, 4.3},
      {"QURU", 20, 21.1, 9.0, 6.6, 6.4},   {"QURU", 40, 39.4, 13.5, 10.8, 9.9},
  };
  /* Half the last printed digit: the computed value rounds to the printed one. */
  const double tol = 0.05 + 1e-9;
  sylva_utdb *u = builtin();
  for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
    const sylva_utdb_species *s = must_find(u, "NoEast", rows[i].code);
    sylva_utdb_sizes z, zc;
    CHECK_INT(sylva_utdb_chain(s, rows[i].age, false, &z), SYLVA_OK);
    CHECK_NEAR(z.age, rows[i].age, 0);
    CHECK_NEAR(z.dbh_cm, rows[i].dbh, tol);
    CHECK_NEAR(z.height_m, rows[i].height, tol);
    CHECK_NEAR(z.crown_dia_m, rows[i].crown_dia, tol);
    CHECK_NEAR(z.crown_ht_m, rows[i].crown_ht, tol);
    CHECK(isfinite(z.leaf_area_m2) && z.leaf_area_m2 > 0);
    /* These ages are inside the range and no curve turns over before them. */
    CHECK_INT(sylva_utdb_chain(s, rows[i].age, true, &zc), SYLVA_OK);
    CHECK_NEAR(zc.dbh_cm, z.dbh_cm, 1e-12);
    CHECK_NEAR(zc.height_m, z.height_m, 1e-12);
    CHECK_NEAR(zc.crown_dia_m, z.crown_dia_m, 1e-12);
    CHECK_NEAR(zc.crown_ht_m, z.crown_ht_m, 1e-12);
  }
  /* loglogw1 with the term inside the inner log reproduces the archive's Apps:
   * NoEast PLAC crown diameter over the dbh range 2.4..61.76 is 0.78..14.63. */
  const sylva_utdb_species *s = must_find(u, "NoEast", "PLAC");
  CHECK_NEAR(sylva_utdb_eval(&s->curve[SYLVA_UTDB_CROWN_DIA], 2.4), 0.78, 0.005);
  CHECK_NEAR(sylva_utdb_eval(&s->curve[SYLVA_UTDB_CROWN_DIA], 61.76), 14.63, 0.005);
  CHECK_NEAR(sylva_utdb_eval(&s->curve[SYLVA_UTDB_LEAF_AREA], 61.76), 562.5, 0.05);

  sylva_utdb_sizes z;
  CHECK_INT(sylva_utdb_chain(s, -1, false, &z), SYLVA_ERANGE);
  CHECK(isnan(z.dbh_cm) && isnan(z.height_m));
  CHECK_INT(sylva_utdb_chain(s, NAN, true, &z), SYLVA_ERANGE);
  CHECK_INT(sylva_utdb_chain(s, INFINITY, true, &z), SYLVA_ERANGE);
  /* No age -> dbh equation: all NAN. */
  CHECK_INT(sylva_utdb_chain(must_find(u, "CenFla", "SAPA"), 10, true, &z), SYLVA_OK);
  CHECK(isnan(z.dbh_cm) && isnan(z.height_m) && isnan(z.leaf_area_m2));
  sylva_utdb_free(u);
}

static sylva_utdb_curve curve(const char *form, double a, double b, double c, double d,
                              double e) {
  sylva_utdb_curve cv = {.present = true, .a = a, .b = b, .c = c, .d = d, .e = e, .mse = c,
                         .x_min = 0, .x_max = INFINITY};
  snprintf(cv.form, sizeof cv.form, "%s", form);
  return cv;
}

/* Each form at x = 20 with a = 0.5, b = 0.8, c = mse = 0.04, d = -0.001, e = 2e-5,
 * against values computed by hand (Python, double precision) from TS4 and the errata:
 * the weight multiplies mse/2, loglogw1 has the term inside the inner log. */
static void test_forms(void) {
  static const struct {
    const char *form;
    double value;
  } forms[] = {
      {"lin", 16.5},                      /* 0.5 + 0.8*20 */
      {"quad", 32.5},                     /* + 0.04*400 */
      {"cub", 24.5},                      /* - 0.001*8000 */
      {"quart", 27.7},                    /* + 2e-5*160000 */
      {"loglogw1", 4.0386617883405993},   /* exp(0.5 + 0.8 ln(ln 21 + 0.02)) */
      {"loglogw2", 4.3934639133197244},   /* exp(0.5 + 0.8 ln ln 21 + √20 0.02) */
      {"loglogw3", 5.9934981690038347},   /* exp(0.5 + 0.8 ln ln 21 + 20 0.02) */
      {"loglogw4", 11976.183438617516},   /* exp(0.5 + 0.8 ln ln 21 + 400 0.02) */
      {"expow1", 14946683.593774399},     /* exp(0.5 + 16 + 0.02) */
      {"expow2", 16021509.4674275},       /* exp(0.5 + 16 + √20 0.02) */
      {"expow3", 21856305.082325634},     /* exp(0.5 + 16 + 20 0.02) */
      {"expow4", 43673179097.646416},     /* exp(0.5 + 16 + 400 0.02) */
  };
  for (size_t i = 0; i < sizeof forms / sizeof forms[0]; i++) {
    sylva_utdb_curve cv = curve(forms[i].form, 0.5, 0.8, 0.04, -0.001, 2e-5);
    double v = sylva_utdb_eval(&cv, 20);
    if (fabs(v - forms[i].value) > 1e-12 * fabs(forms[i].value))
      fprintf(stderr, "form %s\n", forms[i].form);
    CHECK_NEAR(v, forms[i].value, 1e-12 * fabs(forms[i].value));
  }
  /* Coefficients a form does not use are not part of it. */
  sylva_utdb_curve lin = curve("lin", 0.5, 0.8, 0.04, -0.001, 2e-5);
  CHECK_NEAR(sylva_utdb_eval(&lin, 2), 2.1, 1e-12);
  sylva_utdb_curve quad = curve("quad", 1, 0, 1, 5, 5);
  CHECK_NEAR(sylva_utdb_eval(&quad, 3), 10, 1e-12);
  /* The log and exponential forms read the MSE from mse. */
  sylva_utdb_curve e1 = curve("expow1", 0, 0, 99, 0, 0);
  e1.mse = 0.5;
  CHECK_NEAR(sylva_utdb_eval(&e1, 7), exp(0.25), 1e-12);
  /* An absent curve, an unknown form, no curve. */
  sylva_utdb_curve absent = curve("lin", 1, 1, 0, 0, 0);
  absent.present = false;
  CHECK(isnan(sylva_utdb_eval(&absent, 1)));
  CHECK(isnan(sylva_utdb_eval_clamped(&absent, 1)));
  sylva_utdb_curve unknown = curve("cubic", 1, 1, 0, 0, 0);
  CHECK(isnan(sylva_utdb_eval(&unknown, 1)));
  CHECK(isnan(sylva_utdb_eval_clamped(&unknown, 1)));
  CHECK(isnan(sylva_utdb_eval(NULL, 1)));
  CHECK(isnan(sylva_utdb_eval_clamped(&lin, NAN)));
}

/* Clamping: x held to the range, and a curve that turns over held at its peak. */
static void test_clamping(void) {
  sylva_utdb *u = builtin();
  /* InlVal CESI4 (Chinese hackberry): age -> dbh is 2.5184 + 2.16011 age - 0.01839
   * age², ages 1..70; it peaks at age 58.73 (dbh 65.95, its Apps max) and falls to
   * 63.62 by age 70. */
  const sylva_utdb_species *s = must_find(u, "InlVal", "CESI4");
  const sylva_utdb_curve *dbh = &s->curve[SYLVA_UTDB_DBH];
  CHECK_NEAR(s->age_min, 1, 0);
  CHECK_NEAR(s->age_max, 70, 0);
  double peak_age = -2.16011 / (2 * -0.01839), peak = sylva_utdb_eval(dbh, peak_age);
  CHECK_NEAR(peak, 65.95, 0.005);
  CHECK_NEAR(sylva_utdb_eval(dbh, 70), 63.6151, 1e-9);
  CHECK_NEAR(sylva_utdb_eval_clamped(dbh, 70), peak, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(dbh, 500), peak, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(dbh, 30), sylva_utdb_eval(dbh, 30), 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(dbh, 0), sylva_utdb_eval(dbh, 1), 1e-12); /* age_min */
  CHECK_NEAR(sylva_utdb_eval_clamped(dbh, 0), 4.66012, 1e-9);
  sylva_utdb_sizes z;
  CHECK_INT(sylva_utdb_chain(s, 70, true, &z), SYLVA_OK);
  CHECK_NEAR(z.dbh_cm, peak, 1e-12);
  CHECK_INT(sylva_utdb_chain(s, 70, false, &z), SYLVA_OK);
  CHECK_NEAR(z.dbh_cm, 63.6151, 1e-9);

  /* CenFla CICA (camphor tree): dbh -> height is a cubic that peaks at dbh 63 (12.1 m)
   * and falls to 5.4 m at the end of its dbh range (150.7 cm). */
  const sylva_utdb_curve *ht = &must_find(u, "CenFla", "CICA")->curve[SYLVA_UTDB_HEIGHT];
  CHECK(strcmp(ht->form, "cub") == 0);
  CHECK_NEAR(ht->x_max, 150.7, 0);
  CHECK_NEAR(sylva_utdb_eval(ht, 150.7), 5.38, 0.01);
  CHECK_NEAR(sylva_utdb_eval_clamped(ht, 150.7), 12.08, 0.01);
  CHECK(sylva_utdb_eval_clamped(ht, 150.7) >= sylva_utdb_eval(ht, 63.2));

  /* Synthetic curves, one per kind of stationary point. */
  sylva_utdb_curve cub = curve("cub", 0, 3, 0, -1, 0); /* 3x - x³: peak 2 at x = 1 */
  cub.x_max = 5;
  CHECK_NEAR(sylva_utdb_eval_clamped(&cub, 3), 2, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(&cub, 0.5), 1.375, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(&cub, -4), 0, 1e-12);
  sylva_utdb_curve quart = curve("quart", 0, 0, 2, 0, -1); /* 2x² - x⁴: peak 1 at x = 1 */
  quart.x_max = 3;
  CHECK_NEAR(sylva_utdb_eval_clamped(&quart, 2), 1, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(&quart, 10), 1, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(&quart, 0.5), 0.4375, 1e-12);
  sylva_utdb_curve quad = curve("quad", 1, 4, -1, 0, 0); /* 1 + 4x - x²: peak 5 at x = 2 */
  quad.x_min = 1;
  quad.x_max = 6;
  CHECK_NEAR(sylva_utdb_eval_clamped(&quad, 0), 4, 1e-12);
  CHECK_NEAR(sylva_utdb_eval_clamped(&quad, 5), 5, 1e-12);
  /* expow2 with b < 0: exp(-0.1 x + 0.4 √x) peaks at x = (0.8 / 0.4)² = 4. */
  sylva_utdb_curve e2 = curve("expow2", 0, -0.1, 0.8, 0, 0);
  e2.x_max = 10;
  CHECK_NEAR(sylva_utdb_eval_clamped(&e2, 9), exp(0.4), 1e-12);
  /* A falling curve stays at its value at x_min. */
  sylva_utdb_curve fall = curve("lin", 10, -1, 0, 0, 0);
  fall.x_min = 2;
  fall.x_max = 8;
  CHECK_NEAR(sylva_utdb_eval_clamped(&fall, 7), 8, 1e-12);
  /* A reversed range applies nowhere. */
  fall.x_min = 9;
  CHECK(isnan(sylva_utdb_eval_clamped(&fall, 7)));

  /* Every curve of the tables, clamped, never falls along its range and is the running
   * maximum of the published curve (compared on a grid of 2000 steps, which can miss a
   * peak by a little; 0..50 where the range is open). */
  for (int i = 0; i < sylva_utdb_count(u); i++) {
    const sylva_utdb_species *sp = sylva_utdb_at(u, i);
    for (int m = 0; m < SYLVA_UTDB_MEASURES; m++) {
      const sylva_utdb_curve *c = &sp->curve[m];
      if (!c->present) continue;
      double lo = c->x_min, hi = isfinite(c->x_max) ? c->x_max : 50;
      double prev = -INFINITY, seen = -INFINITY;
      int bad = 0;
      for (int k = 0; k <= 2000; k++) {
        double x = lo + (hi - lo) * k / 2000.0;
        double v = sylva_utdb_eval_clamped(c, x);
        seen = fmax(seen, sylva_utdb_eval(c, x));
        double slack = 1e-9 * (1 + fabs(v));
        if (!(v >= prev - slack) || !(v >= seen - slack) ||
            !(v <= seen + 1e-3 * (1 + fabs(seen))))
          bad++;
        prev = v;
      }
      if (bad) fprintf(stderr, "%s %s measure %d: %d bad points\n", sp->region, sp->code, m, bad);
      CHECK_INT(bad, 0);
    }
    /* And the chained sizes never shrink with age. */
    sylva_utdb_sizes last = {0};
    for (double age = 0; age <= 160 && sylva_utdb_complete(sp); age += 0.5) {
      sylva_utdb_sizes z2;
      CHECK_INT(sylva_utdb_chain(sp, age, true, &z2), SYLVA_OK);
      if (age > 0 &&
          !(z2.dbh_cm >= last.dbh_cm && z2.height_m >= last.height_m &&
            z2.crown_dia_m >= last.crown_dia_m && z2.crown_ht_m >= last.crown_ht_m)) {
        fprintf(stderr, "%s %s shrinks at age %g\n", sp->region, sp->code, age);
        CHECK(0);
        break;
      }
      last = z2;
    }
  }
  sylva_utdb_free(u);
}

/* The species a growing tree can use: all four of dbh, height, crown diameter and
 * crown height. */
static void test_complete_species(void) {
  /* NoEast (Queens, NY): all 21 of its species, listed from TS6. */
  static const char *const noeast[] = {"ACPL", "ACRU", "ACSA1", "ACSA2", "AEHI", "FRPE",  "GIBI",
                                       "GLTR", "LIST", "MA2",   "PIST",  "PLAC", "PRSE2", "PYCA",
                                       "QUPA", "QUPH", "QURU",  "TICO",  "TITO", "ULAM",  "ZESE"};
  /* InlVal (Modesto, CA): the urban-site species, with their TS2 common names. */
  static const struct {
    const char *code, *common;
  } inlval[] = {{"PLAC", "London planetree"},   {"ACSA1", "silver maple"},
                {"FRVE_G", "Modesto ash"},      {"KOPA", "goldenrain tree"},
                {"MAGR", "southern magnolia"},  {"PICH", "Chinese pistache"},
                {"CESI4", "Chinese hackberry"}};
  sylva_utdb *u = builtin();
  int n = (int)(sizeof noeast / sizeof noeast[0]);
  CHECK_INT(n, 21);
  for (int i = 0; i < n; i++) {
    const sylva_utdb_species *s = must_find(u, "NoEast", noeast[i]);
    CHECK(sylva_utdb_complete(s));
    CHECK(s->curve[SYLVA_UTDB_LEAF_AREA].present);
    CHECK(!isnan(s->age_min) && !isnan(s->age_max));
  }
  int complete = 0, listed = 0;
  for (int i = 0; i < sylva_utdb_count(u); i++) {
    const sylva_utdb_species *s = sylva_utdb_at(u, i);
    if (strcmp(s->region, "NoEast") != 0) continue;
    complete += sylva_utdb_complete(s);
    for (int k = 0; k < n; k++) listed += strcmp(s->code, noeast[k]) == 0;
  }
  CHECK_INT(complete, 21);
  CHECK_INT(listed, 21);
  for (size_t i = 0; i < sizeof inlval / sizeof inlval[0]; i++) {
    const sylva_utdb_species *s = must_find(u, "InlVal", inlval[i].code);
    CHECK(sylva_utdb_complete(s));
    if (strcmp(s->common, inlval[i].common) != 0)
      fprintf(stderr, "InlVal %s is '%s'\n", inlval[i].code, s->common);
    CHECK(strcmp(s->common, inlval[i].common) == 0);
  }
  CHECK(sylva_utdb_find(u, "InlVal", "PLAC2") == NULL);
  CHECK(sylva_utdb_find(u, "InlVal", "CESI") == NULL);
  sylva_utdb_free(u);
}

/* ---- Bad input ---- */

#define TS6_HEADER                                                                        \
  "Region,Scientific Name,SpCode,Independent variable,Predicts component ,Units of "    \
  "predicted components,Model weight,EqName,a,b,c,d,e,Apps min,Apps max,Sigma,n,adj "   \
  "R2,Data min (from raw data),Data max (from raw data),DF\n"
#define TS6_AGE "NoEast,Platanus x acerifolia,PLAC,age,dbh,centimeters,1/age,quad,2.40322,1.2942,-0.00705,,,2.4,61.76,0.8,49,0.889,2.8,164.6,46\n"
#define TS6_HT "NoEast,Platanus x acerifolia,PLAC,dbh,tree ht,meters,1/dbh,quad,3.29515,0.30021,-0.00109,,,4.01,17.69,0.1,53,0.892,5.5,33,50\n"
#define TS2_TEXT                                                                          \
  "Region,Scientific Name,Common Name,SpCode,Tree Type,Dbh_class1,Grand Total\n"        \
  "NoEast,Platanus x acerifolia,London planetree,PLAC,BDL,3,49\n"

/* Parses TS6 text (with TS2_TEXT) and expects rc; when want is given, err must hold it. */
static void expect(const char *ts6, const char *ts2, int rc, const char *want) {
  static int sentinel;
  char err[256] = "untouched";
  sylva_utdb *u = (sylva_utdb *)&sentinel; /* must become NULL on failure */
  int got = sylva_utdb_parse(ts6, strlen(ts6), ts2, strlen(ts2), &u, err, sizeof err);
  CHECK_INT(got, rc);
  if (got) CHECK(u == NULL);
  if (want && !strstr(err, want)) {
    fprintf(stderr, "error '%s' lacks '%s'\n", err, want);
    CHECK(0);
  }
  if (!got) CHECK(err[0] == '\0');
  sylva_utdb_free(got ? NULL : u);
}

static void test_bad_input(void) {
  /* The good text, then CSV variants that mean the same: CRLF, quotes, blank lines. */
  expect(TS6_HEADER TS6_AGE TS6_HT, TS2_TEXT, SYLVA_OK, NULL);
  expect("Region,Scientific Name,SpCode,Independent variable,\"Predicts component \",EqName,a,b,"
         "c,d,e,Apps min,Apps max,n,adj R2,Data min (from raw data),Data max (from raw data)\r\n"
         "\"NoEast\",\"Platanus, x \"\"acerifolia\"\"\",PLAC,age,dbh,quad,2.4,1.29,-0.007,,,"
         "2.4,61.76,49,0.889,2.8,164.6\r\n\r\n",
         TS2_TEXT, SYLVA_OK, NULL);
  {
    const char *ts6 = TS6_HEADER "\n" TS6_AGE "\n" TS6_HT;
    sylva_utdb *u = NULL;
    char err[128];
    CHECK_INT(sylva_utdb_parse(ts6, strlen(ts6), TS2_TEXT, strlen(TS2_TEXT), &u, err, sizeof err),
              SYLVA_OK);
    CHECK_INT(sylva_utdb_count(u), 1);
    const sylva_utdb_species *s = sylva_utdb_find(u, "NoEast", "PLAC");
    CHECK(s && s->curve[SYLVA_UTDB_DBH].present && s->curve[SYLVA_UTDB_HEIGHT].present);
    CHECK(s && !sylva_utdb_complete(s));
    CHECK(s && strcmp(s->common, "London planetree") == 0);
    /* No dbh -> age row: ages are held to >= 0 only. */
    CHECK(s && isnan(s->age_min) && s->curve[SYLVA_UTDB_DBH].x_min == 0 &&
          isinf(s->curve[SYLVA_UTDB_DBH].x_max));
    sylva_utdb_free(u);
  }

  /* A short row. */
  expect(TS6_HEADER TS6_AGE
         "NoEast,Platanus x acerifolia,PLAC,dbh,tree ht,meters,1/dbh,quad,3.29515,0.30021\n",
         TS2_TEXT, SYLVA_EINVAL,
         "TS6_Growth_coefficients.csv:3: 10 fields where the header has 21");
  /* A non-numeric coefficient, and one with trailing junk. */
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,quad,x1.5,1.2942,-0.00705,,,2.4,61.76,0.8,49,"
                    "0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, "TS6_Growth_coefficients.csv:2: column 9 (a): 'x1.5' is not a number");
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,quad,1.5,1.2942e,-0.00705,,,2.4,61.76,0.8,49,"
                    "0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 10 (b): '1.2942e' is not a number");
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,quad,1.5,inf,-0.00705,,,2.4,61.76,0.8,49,"
                    "0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 10 (b): 'inf' is not a number");
  /* An unknown form. */
  expect(TS6_HEADER TS6_HT "NoEast,P,PLAC,age,dbh,cm,1,loglogw9,1.5,1.2,0.01,,,2.4,61.76,0.8,49,"
                           "0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL,
         "TS6_Growth_coefficients.csv:3: column 8 (EqName): unknown equation form 'loglogw9'");
  /* A coefficient the form needs is missing (cub needs d). */
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,cub,1.5,1.2,0.01,,,2.4,61.76,0.8,49,0.889,2.8,"
                    "164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 12 (d): empty");
  /* A negative MSE. */
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,loglogw2,1.5,1.2,-0.01,,,2.4,61.76,0.8,49,0.889,"
                    "2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 11 (c): the MSE of a loglogw2 equation is negative");
  /* An equation TS6 never has, and one given twice. */
  expect(TS6_HEADER "NoEast,P,PLAC,age,tree ht,m,1,lin,1.5,1.2,,,,2.4,61.76,0.8,49,0.889,2.8,"
                    "164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: columns 4 and 5: no such equation as 'age' -> 'tree ht'");
  expect(TS6_HEADER TS6_HT TS6_AGE TS6_HT, TS2_TEXT, SYLVA_EINVAL,
         ":4: a second 'dbh' -> 'tree ht' equation for NoEast PLAC");
  /* A bad count, an over-long name, an empty code. */
  expect(TS6_HEADER "NoEast,P,PLAC,age,dbh,cm,1,lin,1.5,1.2,,,,2.4,61.76,0.8,4.9,0.889,2.8,"
                    "164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 17 (n): '4.9' is not a count");
  expect(TS6_HEADER "NoEast,P,PLACPLACPLACPLACPLAC,age,dbh,cm,1,lin,1.5,1.2,,,,2.4,61.76,0.8,49,"
                    "0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 3 (SpCode): longer than 15 characters");
  expect(TS6_HEADER "NoEast,P,,age,dbh,cm,1,lin,1.5,1.2,,,,2.4,61.76,0.8,49,0.889,2.8,164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, ":2: column 3 (SpCode): empty");
  /* Broken quoting, a NUL byte, a header without a needed column, nothing at all. */
  expect(TS6_HEADER "NoEast,\"P\"x,PLAC,age,dbh,cm,1,lin,1.5,1.2,,,,2.4,61.76,0.8,49,0.889,2.8,"
                    "164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, "TS6_Growth_coefficients.csv:2: malformed quoting");
  expect(TS6_HEADER "NoEast,\"P,PLAC,age,dbh,cm,1,lin,1.5,1.2,,,,2.4,61.76,0.8,49,0.889,2.8,"
                    "164.6,46\n",
         TS2_TEXT, SYLVA_EINVAL, "malformed quoting");
  {
    char ts6[] = TS6_HEADER TS6_AGE;
    size_t len = strlen(ts6);
    ts6[strlen(TS6_HEADER) + 3] = '\0'; /* in "NoEast" */
    sylva_utdb *u = NULL;
    char err[160];
    CHECK_INT(sylva_utdb_parse(ts6, len, TS2_TEXT, strlen(TS2_TEXT), &u, err, sizeof err),
              SYLVA_EINVAL);
    CHECK(strstr(err, "TS6_Growth_coefficients.csv:2: column 1: a NUL byte") != NULL);
    CHECK(u == NULL);
  }
  expect("Region,SpCode,a\nNoEast,PLAC,1\n", TS2_TEXT, SYLVA_EINVAL,
         "TS6_Growth_coefficients.csv:1: the header has no column 'Scientific Name'");
  expect("", TS2_TEXT, SYLVA_EINVAL, "TS6_Growth_coefficients.csv: empty: no header row");
  /* TS2's errors name TS2. */
  expect(TS6_HEADER TS6_AGE, "Region,Scientific Name,Common Name,SpCode,Tree Type\nNoEast,P\n",
         SYLVA_EINVAL, "TS2_Regional_species_and_counts.csv:2: 2 fields where the header has 5");
  expect(TS6_HEADER TS6_AGE, TS2_TEXT "NoEast,P,plane,PLAC,BDL,1,2\n", SYLVA_EINVAL,
         "TS2_Regional_species_and_counts.csv:3: species NoEast PLAC again (first on line 2)");

  /* A small err buffer is cut, not overrun; no buffer at all is allowed. */
  {
    const char *ts6 = TS6_HEADER "x\n";
    char err[12];
    memset(err, 'z', sizeof err);
    sylva_utdb *u = NULL;
    CHECK_INT(sylva_utdb_parse(ts6, strlen(ts6), TS2_TEXT, strlen(TS2_TEXT), &u, err, 8),
              SYLVA_EINVAL);
    CHECK(strlen(err) == 7 && err[8] == 'z');
    CHECK_INT(sylva_utdb_parse(ts6, strlen(ts6), TS2_TEXT, strlen(TS2_TEXT), &u, NULL, 0),
              SYLVA_EINVAL);
    CHECK(u == NULL);
  }
}

/* The real tables cut short or with bytes changed: a status, never a crash (the
 * sanitizer build watches memory). */
static void test_damaged_tables(void) {
  int ok = 0, failed = 0;
  for (size_t cut = 0; cut < sylva__utdb_ts6_len; cut += sylva__utdb_ts6_len / 97 + 1) {
    sylva_utdb *u = NULL;
    char err[256];
    int rc = sylva_utdb_parse(sylva__utdb_ts6, cut, sylva__utdb_ts2, sylva__utdb_ts2_len, &u,
                              err, sizeof err);
    CHECK(rc == SYLVA_OK || rc == SYLVA_EINVAL);
    if (rc) CHECK(u == NULL && strncmp(err, "TS6_Growth_coefficients.csv", 27) == 0);
    rc ? failed++ : ok++;
    sylva_utdb_free(u);
  }
  CHECK(ok > 0 && failed > 0);
  char *copy = malloc(sylva__utdb_ts6_len);
  CHECK(copy != NULL);
  if (!copy) return;
  uint32_t state = 12345;
  static const char bytes[] = {',', '"', '\n', '\r', 'x', '-', '.', ' ', '\0', (char)0xff};
  for (int round = 0; round < 60; round++) {
    memcpy(copy, sylva__utdb_ts6, sylva__utdb_ts6_len);
    for (int k = 0; k < 4; k++) {
      state = state * 1664525u + 1013904223u;
      size_t at = (state >> 8) % sylva__utdb_ts6_len;
      copy[at] = bytes[(state >> 4) % sizeof bytes];
    }
    sylva_utdb *u = NULL;
    char err[256];
    int rc = sylva_utdb_parse(copy, sylva__utdb_ts6_len, sylva__utdb_ts2, sylva__utdb_ts2_len,
                              &u, err, sizeof err);
    CHECK(rc == SYLVA_OK || rc == SYLVA_EINVAL);
    CHECK((rc == SYLVA_OK) == (u != NULL));
    sylva_utdb_free(u);
  }
  free(copy);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(builtin_counts), CHECK_TEST(check_values),      CHECK_TEST(forms),
      CHECK_TEST(clamping),       CHECK_TEST(complete_species),  CHECK_TEST(bad_input),
      CHECK_TEST(damaged_tables),
  };
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("utdb");
}
