/* Stands (docs/model.md, "Stands"): the stand's figures hand-worked, a snag that falls
 * and frees its ground, images of dead, standing and fallen stems, and the
 * background death rate against its binomial interval. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../scenario_file.h"
#include "sylva/sylva.h"

#define PI 3.14159265358979323846


static void grow(sylva_world *w, int n) {
  for (int i = 0; i < n; i++) CHECK_INT(sylva_world_step(w, NULL), 0);
}

/* The figures recomputed here from the stems' measures, for roots whose widened hull
 * has area `area`: stems per hectare, basal area, QMD, dominant height (the mean of
 * the `dom` thickest), SDI and the spreads. */
static void check_figures(const sylva_world *w, double area, int dom) {
  sylva_stand_stats st;
  sylva_world_stand(w, &st);
  int n = sylva_world_stem_count(w);
  double ha = area / 10000.0, d2 = 0.0, basal = 0.0, h = 0.0, hh = 0.0, d = 0.0, dd = 0.0;
  int order[16];
  for (int k = 0; k < n; k++) {
    sylva_stem_stats s;
    sylva_world_stem_stats(w, k, &s);
    d2 += s.dbh * s.dbh;
    basal += PI / 4 * s.dbh * s.dbh;
    h += s.height, hh += s.height * s.height, d += s.dbh, dd += s.dbh * s.dbh;
    order[k] = k;
  }
  for (int i = 0; i < n; i++) /* thickest first */
    for (int j = i + 1; j < n; j++) {
      sylva_stem_stats a, b;
      sylva_world_stem_stats(w, order[i], &a);
      sylva_world_stem_stats(w, order[j], &b);
      if (b.dbh > a.dbh) {
        int t = order[i];
        order[i] = order[j], order[j] = t;
      }
    }
  double top = 0.0;
  for (int i = 0; i < dom; i++) {
    sylva_stem_stats s;
    sylva_world_stem_stats(w, order[i], &s);
    top += s.height / dom;
  }
  double qmd = 100.0 * sqrt(d2 / n);
  CHECK_NEAR(st.area, area, 1e-9);
  CHECK_INT(st.alive, n);
  CHECK_NEAR(st.stems_per_ha, n / ha, 1e-6);
  CHECK_NEAR(st.basal_area, basal / ha, 1e-9);
  CHECK_NEAR(st.qmd, qmd, 1e-9);
  CHECK_NEAR(st.sdi, n / ha * pow(qmd / 25.0, 1.605), 1e-6);
  CHECK_NEAR(st.dominant_height, top, 1e-12);
  CHECK_NEAR(st.cv_height, sqrt(hh / n - (h / n) * (h / n)) / (h / n), 1e-9);
  CHECK_NEAR(st.cv_dbh, sqrt(dd / n - (d / n) * (d / n)) / (d / n), 1e-9);
}

#define STAND_JSON(extra, roots)                                                              \
  "{\"format\": \"sylva.scenario/1\", \"seed\": 3, \"iterations\": 30," extra                \
  " \"world\": {\"min\": [-4, -4, 0], \"max\": [6, 6, 10], \"voxel\": 0.1},"                 \
  " \"species\": {\"s\": {\"preset\": \"igm-fig11\", \"growth\": {\"equation\": \"logistic\"," \
  " \"X0\": 2, \"Xm\": 40, \"r\": 0.4}}}, \"plants\": [" roots "]}"

/* Four trees at the corners of a 2 m square: their hull (4 m^2, 8 m around) widened by
 * half their spacing (1 m), 12 + pi m^2; the 100 thickest a hectare are fewer than one
 * here, so the dominant height is the thickest stem's. A fifth at the centre leaves the
 * hull as it is and brings every nearest neighbour to sqrt(2) m. With a stand_area of
 * a hectare the figures are per the hectare, and all four are dominant. */
static void test_hand_worked(void) {
  sylva_world *w = json_world(STAND_JSON("",
      "{\"id\": \"a\", \"species\": \"s\", \"roots\": [[0, 0, 0]]},"
      " {\"id\": \"b\", \"species\": \"s\", \"roots\": [[2, 0, 0]]},"
      " {\"id\": \"c\", \"species\": \"s\", \"roots\": [[0, 2, 0]]},"
      " {\"id\": \"d\", \"species\": \"s\", \"roots\": [[2, 2, 0]]}"));
  grow(w, 14);
  check_figures(w, 12.0 + PI, 1);
  sylva_world_destroy(w);

  w = json_world(STAND_JSON("",
      "{\"id\": \"a\", \"species\": \"s\", \"roots\": [[0, 0, 0]]},"
      " {\"id\": \"b\", \"species\": \"s\", \"roots\": [[2, 0, 0]]},"
      " {\"id\": \"c\", \"species\": \"s\", \"roots\": [[0, 2, 0]]},"
      " {\"id\": \"d\", \"species\": \"s\", \"roots\": [[2, 2, 0]]},"
      " {\"id\": \"e\", \"species\": \"s\", \"roots\": [[1, 1, 0]]}"));
  sylva_stand_stats st;
  sylva_world_stand(w, &st);
  double r = sqrt(2.0) / 2.0;
  CHECK_NEAR(st.area, 4.0 + 8.0 * r + PI * r * r, 1e-12);
  CHECK(isnan(st.qmd) && isnan(st.basal_area) == false); /* planted: no dbh yet */
  sylva_world_destroy(w);

  w = json_world(STAND_JSON(" \"stand_area\": 10000,",
      "{\"id\": \"a\", \"species\": \"s\", \"roots\": [[0, 0, 0]]},"
      " {\"id\": \"b\", \"species\": \"s\", \"roots\": [[2, 0, 0]]},"
      " {\"id\": \"c\", \"species\": \"s\", \"roots\": [[0, 2, 0]]},"
      " {\"id\": \"d\", \"species\": \"s\", \"roots\": [[2, 2, 0]]}"));
  grow(w, 14);
  check_figures(w, 10000.0, 4);
  sylva_world_destroy(w);

  /* one tree: no ground of its own, so nothing per hectare */
  w = json_world(STAND_JSON("", "{\"id\": \"a\", \"species\": \"s\", \"roots\": [[0, 0, 0]]}"));
  grow(w, 14);
  sylva_world_stand(w, &st);
  sylva_stem_stats s;
  sylva_world_stem_stats(w, 0, &s);
  CHECK(isnan(st.area) && isnan(st.stems_per_ha) && st.alive == 1);
  CHECK_NEAR(st.qmd, 100.0 * s.dbh, 1e-12);
  CHECK_NEAR(st.dominant_height, s.height, 0.0);
  sylva_world_destroy(w);
}

/* A linden that dies in its first season (a background rate of 1) and whose snag
 * stands one season, at the origin (world a) or 8 m away (world b): it loses its
 * leafy twigs at once and keeps its measures, then falls with every node. A seedling
 * planted at the origin then grows in a exactly as in b, where no tree ever stood:
 * the fallen tree's voxels and shade are free (docs/model.md, "Stands"). */
#define SNAG_JSON(x)                                                                         \
  "{\"format\": \"sylva.scenario/1\", \"seed\": 5, \"iterations\": 30,"                      \
  " \"world\": {\"min\": [-16, -16, 0], \"max\": [16, 16, 20]},"                             \
  " \"species\": {\"doomed\": {\"preset\": \"utdb:NoEast:TICO\", \"mortality\": 1,"         \
  " \"snag_years\": 1}, \"lin\": {\"preset\": \"utdb:NoEast:TICO\"}},"                       \
  " \"plants\": [{\"id\": \"d\", \"species\": \"doomed\", \"roots\": [[" x ", 0, 0]]}]}"

static int64_t stem_nodes(const sylva_world *w, int stem) {
  int64_t n = 0;
  for (size_t i = 0; i < sylva_world_node_count(w); i++) {
    sylva_node_info info;
    sylva_world_node_at(w, i, &info);
    n += sylva_world_stem_index(w, info.plant, info.stem) == stem;
  }
  return n;
}

static void test_snag_falls(void) {
  sylva_world *a = json_world(SNAG_JSON("0")), *b = json_world(SNAG_JSON("8"));
  sylva_stem_stats before, dead, fallen;
  sylva_world_stem_stats(a, 0, &before);
  int64_t planted = stem_nodes(a, 0);
  grow(a, 1);
  grow(b, 1);
  sylva_world_stem_stats(a, 0, &dead);
  CHECK(!dead.alive && dead.died == 1 && dead.fallen == -1);
  CHECK(dead.height == before.height && dead.leaf_area == before.leaf_area &&
        dead.dbh == before.dbh); /* the measures of its last season alive */
  CHECK(stem_nodes(a, 0) > 0 && stem_nodes(a, 0) < planted); /* the leafy twigs went */
  for (size_t i = 0; i < sylva_world_node_count(a); i++) {
    sylva_node_info info;
    sylva_world_node_at(a, i, &info);
    CHECK_INT(info.leaves, 0);
  }
  sylva_stand_stats st;
  sylva_world_stand(a, &st);
  CHECK(st.alive == 0 && st.died == 1);
  grow(a, 1);
  grow(b, 1);
  sylva_world_stem_stats(a, 0, &fallen);
  CHECK(!fallen.alive && fallen.died == 1 && fallen.fallen == 2);
  CHECK_INT(stem_nodes(a, 0), 0);
  sylva_world_stand(a, &st);
  CHECK(st.alive == 0 && st.died == 0);
  /* no shade left anywhere around the origin, to the bit */
  int dark = 0;
  for (double z = 0.05; z < 12; z += 0.25)
    for (double y = -5; y <= 5; y += 0.25)
      for (double x = -5; x <= 5; x += 0.25) dark += sylva_world_light_at(a, (double[3]){x, y, z}) != 1.0;
  CHECK_INT(dark, 0);
  sylva_plant_def seed = {.species = 1, .label = "s", .roots = (const double[][3]){{0, 0, 0}},
                          .root_count = 1};
  CHECK_INT(sylva_world_add_plant(a, &seed, NULL), 1);
  CHECK_INT(sylva_world_add_plant(b, &seed, NULL), 1);
  grow(a, 8);
  grow(b, 8);
  sylva_stem_stats sa, sb;
  sylva_world_stem_stats(a, 1, &sa);
  sylva_world_stem_stats(b, 1, &sb);
  CHECK(sa.nodes == sb.nodes && sa.height == sb.height && sa.dbh == sb.dbh &&
        sa.crown_width == sb.crown_width && sa.light == sb.light && sa.alive && sb.alive);
  CHECK(sa.nodes > 100);
  sylva_world_destroy(a);
  sylva_world_destroy(b);
}

/* An image of a world with a stem alive, one standing dead and one fallen loads to the
 * same world: the same hash and measures, and both grow on alike. */
static void test_image(void) {
  sylva_world *w = json_world(
      "{\"format\": \"sylva.scenario/1\", \"seed\": 9, \"iterations\": 30,"
      " \"world\": {\"min\": [-12, -12, 0], \"max\": [12, 12, 20]},"
      " \"species\": {\"doomed\": {\"preset\": \"utdb:NoEast:TICO\", \"mortality\": 1,"
      " \"snag_years\": 2}, \"lin\": {\"preset\": \"utdb:NoEast:TICO\"}},"
      " \"plants\": [{\"id\": \"d\", \"species\": \"doomed\", \"roots\": [[-6, 0, 0]]},"
      " {\"id\": \"l\", \"species\": \"lin\", \"roots\": [[6, 0, 0]]}]}");
  grow(w, 2);
  sylva_plant_def late = {.species = 0, .label = "d2", .roots = (const double[][3]){{0, 6, 0}},
                          .root_count = 1};
  CHECK_INT(sylva_world_add_plant(w, &late, NULL), 2);
  grow(w, 2); /* d fell at 3, d2 died at 3 and stands */
  sylva_stem_stats s[3];
  for (int k = 0; k < 3; k++) sylva_world_stem_stats(w, k, &s[k]);
  CHECK(s[0].fallen == 3 && s[1].alive && !s[2].alive && s[2].fallen == -1);
  uint8_t *img = NULL;
  size_t n = 0;
  CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
  sylva_world *r = NULL;
  CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
  sylva_free(img);
  if (r) {
    CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    for (int k = 0; k < 3; k++) {
      sylva_stem_stats t;
      sylva_world_stem_stats(r, k, &t);
      CHECK(t.alive == s[k].alive && t.died == s[k].died && t.fallen == s[k].fallen &&
            t.age == s[k].age && t.height == s[k].height && t.leaf_area == s[k].leaf_area &&
            t.crown_area == s[k].crown_area && t.wood_volume == s[k].wood_volume);
    }
    sylva_stand_stats x, y;
    sylva_world_stand(w, &x);
    sylva_world_stand(r, &y);
    CHECK(memcmp(&x, &y, sizeof x) == 0);
    grow(w, 3);
    grow(r, 3);
    CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    sylva_world_destroy(r);
  }
  sylva_world_destroy(w);
}

/* 400 small trees in years with a background death rate of 3% a season, 30 seasons:
 * the survivors are 400 x 0.97^30 = 160.4 expected, within the binomial's 99% interval
 * (2.576 standard deviations, 9.80 each: 135 to 185); each dies once, its died kept.
 * Without the rate none dies. */
static void test_background(void) {
  for (int rate = 0; rate < 2; rate++) {
    char *json = malloc(64 * 1024);
    int k = snprintf(json, 64 * 1024,
                     "{\"format\": \"sylva.scenario/1\", \"seed\": 11, \"iterations\": 30,"
                     " \"world\": {\"min\": [-1, -1, 0], \"max\": [41, 41, 4], \"voxel\": 0.1},"
                     " \"species\": {\"s\": {\"preset\": \"igm-fig11\", \"years\": 1,"
                     " \"mortality\": %s, \"growth\": {\"equation\": \"logistic\", \"X0\": 2,"
                     " \"Xm\": 8, \"r\": 0.3}}}, \"plants\": [",
                     rate ? "0.03" : "0");
    for (int i = 0; i < 400; i++)
      k += snprintf(json + k, 64 * 1024 - (size_t)k,
                    "%s{\"id\": \"t%d\", \"species\": \"s\", \"roots\": [[%d, %d, 0]]}", i ? ", " : "",
                    i, 2 * (i % 20), 2 * (i / 20));
    snprintf(json + k, 64 * 1024 - (size_t)k, "]}");
    sylva_world *w = json_world(json);
    free(json);
    int died_at[400];
    for (int i = 0; i < 400; i++) died_at[i] = -1;
    bool once = true;
    for (int t = 1; t <= 30; t++) {
      const sylva_journal *j;
      CHECK_INT(sylva_world_step(w, &j), 0);
      int now = 0;
      for (int i = 0; i < 400; i++) {
        const sylva_stem_stats *s = &j->stats[i];
        if (died_at[i] >= 0) once &= s->died == died_at[i] && !s->alive;
        else if (!s->alive) died_at[i] = s->died, once &= s->died == t, now++;
      }
      CHECK_INT(j->stand.died, now);
    }
    CHECK(once);
    sylva_stand_stats st;
    sylva_world_stand(w, &st);
    if (rate) {
      printf("background: %d of 400 alive after 30 seasons at 3%% (expected 160.4, 99%%: 135-185)\n",
             st.alive);
      CHECK(st.alive >= 135 && st.alive <= 185);
    } else {
      CHECK_INT(st.alive, 400);
    }
    sylva_world_destroy(w);
  }
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(hand_worked), CHECK_TEST(snag_falls),
                                     CHECK_TEST(image), CHECK_TEST(background)};
  (void)scenario_file; /* the helper header's other reader */
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("stand");
}
