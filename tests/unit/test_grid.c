/* The voxel environment: pyramid and column shade on a small grid, light, exact
 * removal (one by one and in batches on threads), occupancy and its memory given
 * back, obstacles, and a 500-million-voxel site that costs memory only where
 * something is. */
#include <string.h>

#include "../check.h"
#include "grid.h"
#include "rng.h"

static int64_t fixed(double v) { return (int64_t)floor(v * SYLVA__SHADE_ONE + 0.5); }

/* Stamps the pyramid these tests define: half-width floor(q / 2), and the column
 * below the base at the deepest layer's value. */
static int stamp(sylva__grid *g, const int v[3], int depth, const int64_t *w, int sign) {
  sylva__pyramid p = {.depth = depth, .column = w[depth - 1]};
  for (int q = 1; q <= depth; q++) {
    p.w[q - 1] = w[q - 1];
    p.half[q - 1] = q / 2;
  }
  return sylva__grid_stamp(g, v, &p, sign);
}

static void test_pyramid_and_column(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {2, 2, 2};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  CHECK_INT(g.n[0], 40);
  int64_t w[4];
  for (int q = 1; q <= 4; q++) w[q - 1] = fixed(pow(2.0, -q)); /* b = 2 */
  int v[3] = {20, 20, 30};
  CHECK_INT(stamp(&g, v, 4, w, +1), 0);
#define S(x, y, z) sylva__grid_shade_raw(&g, (int[3]){x, y, z})
  CHECK_INT(S(20, 20, 30), 0);         /* own voxel */
  CHECK_INT(S(20, 20, 31), 0);         /* above */
  CHECK_INT(S(20, 20, 29), w[0]);      /* q = 1: one voxel */
  CHECK_INT(S(21, 20, 29), 0);
  CHECK_INT(S(21, 21, 28), w[1]);      /* q = 2: half-width 1 */
  CHECK_INT(S(22, 20, 28), 0);
  CHECK_INT(S(19, 21, 27), w[2]);      /* q = 3: half-width 1 */
  CHECK_INT(S(22, 20, 27), 0);
  CHECK_INT(S(22, 22, 26), w[3]);      /* q = 4: half-width 2 */
  CHECK_INT(S(23, 20, 26), 0);
  /* column below the base: w[3] per voxel down to the ground */
  CHECK_INT(S(22, 22, 25), w[3]);
  CHECK_INT(S(18, 18, 10), w[3]);
  CHECK_INT(S(20, 20, 0), w[3]);
  CHECK_INT(S(20, 20, 16), w[3]); /* across block borders */
  CHECK_INT(S(20, 20, 15), w[3]);
  CHECK_INT(S(23, 20, 10), 0);
  CHECK_NEAR(sylva__grid_light(&g, (int[3]){20, 20, 29}), 0.5, 1e-9);
  CHECK_NEAR(sylva__grid_light(&g, (int[3]){20, 20, 5}), 1.0 - 1.0 / 16.0, 1e-9);
  /* a second node above adds: light falls, never below 0 */
  int v2[3] = {20, 20, 31};
  CHECK_INT(stamp(&g, v2, 4, w, +1), 0);
  CHECK_INT(S(20, 20, 29), w[0] + w[1]);
  for (int i = 0; i < 4; i++) CHECK_INT(stamp(&g, v2, 4, w, +1), 0);
  CHECK_NEAR(sylva__grid_light(&g, (int[3]){20, 20, 30}), 0.0, 0.0);
  /* near the world's edge the pyramid is clipped, nothing crashes */
  int edge[3] = {0, 39, 3};
  CHECK_INT(stamp(&g, edge, 4, w, +1), 0);
  CHECK_INT(S(0, 39, 2), w[0]);
  CHECK_INT(S(1, 38, 1), w[1]);
#undef S
  sylva__grid_free(&g);
}

/* Every voxel of two grids equal (over the chunks either one has). */
static int grids_equal(const sylva__grid *a, const sylva__grid *b) {
  for (int z = 0; z < a->n[2]; z++)
    for (int y = 0; y < a->n[1]; y++)
      for (int x = 0; x < a->n[0]; x++) {
        int v[3] = {x, y, z};
        if (sylva__grid_shade_raw(a, v) != sylva__grid_shade_raw(b, v)) return 0;
      }
  return 1;
}

/* The voxels of g with any shade. */
static long shaded_voxels(const sylva__grid *g) {
  long n = 0;
  for (int z = 0; z < g->n[2]; z++)
    for (int y = 0; y < g->n[1]; y++)
      for (int x = 0; x < g->n[0]; x++) n += sylva__grid_shade_raw(g, (int[3]){x, y, z}) != 0;
  return n;
}

static void test_exact_removal(void) {
  sylva__grid g, h, empty;
  double mn[3] = {-1, -1, 0}, mx[3] = {1, 1, 3};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  CHECK_INT(sylva__grid_init(&h, mn, mx, 0.05), 0);
  CHECK_INT(sylva__grid_init(&empty, mn, mx, 0.05), 0);
  sylva__rng r;
  sylva__rng_seed(&r, 7);
  enum { N = 300 };
  int vox[N][3];
  int64_t w[N][20];
  int depth[N];
  for (int i = 0; i < N; i++) {
    for (int a = 0; a < 3; a++) vox[i][a] = (int)sylva__rng_below(&r, (uint32_t)g.n[a]);
    depth[i] = 1 + (int)sylva__rng_below(&r, 20);
    double b = 1.8 + 0.7 * sylva__rng_unit(&r);
    for (int q = 1; q <= 20; q++) w[i][q - 1] = fixed(pow(b, -q));
    CHECK_INT(stamp(&g, vox[i], depth[i], w[i], +1), 0);
  }
  /* remove the odd ones in reverse order; stamp only the even ones into h */
  for (int i = N - 1; i >= 0; i--)
    if (i % 2) CHECK_INT(stamp(&g, vox[i], depth[i], w[i], -1), 0);
  for (int i = 0; i < N; i += 2) CHECK_INT(stamp(&h, vox[i], depth[i], w[i], +1), 0);
  CHECK(grids_equal(&g, &h));
  for (int i = 0; i < N; i += 2) CHECK_INT(stamp(&g, vox[i], depth[i], w[i], -1), 0);
  CHECK(grids_equal(&g, &empty)); /* equal to never having added */
  sylva__grid_free(&g);
  sylva__grid_free(&h);
  sylva__grid_free(&empty);
}

/* The grid against the definition, voxel by voxel: 60 random nodes on a grid of mx
 * metres (near chunk borders and the world's edges too), each voxel's S summed
 * directly from docs/model.md. */
static void against_definition(const double mx[3], uint64_t seed) {
  sylva__grid g;
  double mn[3] = {0, 0, 0};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  sylva__rng r;
  sylva__rng_seed(&r, seed);
  enum { N = 60 };
  int vox[N][3], depth[N];
  int64_t w[N][20];
  for (int i = 0; i < N; i++) {
    for (int a = 0; a < 3; a++) vox[i][a] = (int)sylva__rng_below(&r, (uint32_t)g.n[a]);
    depth[i] = 1 + (int)sylva__rng_below(&r, 20);
    for (int q = 1; q <= 20; q++) w[i][q - 1] = fixed(pow(1.8 + 0.01 * i, -q));
    CHECK_INT(stamp(&g, vox[i], depth[i], w[i], +1), 0);
  }
  long bad = 0;
  for (int z = 0; z < g.n[2]; z++)
    for (int y = 0; y < g.n[1]; y++)
      for (int x = 0; x < g.n[0]; x++) {
        int64_t expect = 0;
        for (int i = 0; i < N; i++) {
          int q = vox[i][2] - z, dx = abs(x - vox[i][0]), dy = abs(y - vox[i][1]);
          if (q >= 1 && q <= depth[i] && dx <= q / 2 && dy <= q / 2) expect += w[i][q - 1];
          if (q > depth[i] && dx <= depth[i] / 2 && dy <= depth[i] / 2) expect += w[i][depth[i] - 1];
        }
        bad += sylva__grid_shade_raw(&g, (int[3]){x, y, z}) != expect;
      }
  CHECK_INT(bad, 0);
  sylva__grid_free(&g);
}

/* A column whose top lies in the upper half of its block is held by the block sum
 * above, less the layers above its top; in the highest row of blocks (48 voxels: the
 * third) there is no block above, and it is written layer by layer. */
static void test_against_definition(void) {
  against_definition((double[3]){2.2, 1.9, 3.3}, 11);
  against_definition((double[3]){1.6, 1.6, 2.4}, 12);
}

static void test_occupancy(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  int v[3] = {3, 4, 5};
  CHECK_INT(sylva__grid_occupant(&g, v), -1);
  CHECK_INT(sylva__grid_occupy(&g, v, 7), 0);
  CHECK_INT(sylva__grid_occupant(&g, v), 7);
  CHECK_INT(sylva__grid_occupy(&g, v, 8), SYLVA_EOCCUPIED); /* another stem */
  CHECK_INT(sylva__grid_occupy(&g, v, 7), 0);               /* same stem again */
  sylva__grid_vacate(&g, v);
  CHECK_INT(sylva__grid_occupant(&g, v), 7); /* one node of stem 7 is still there */
  sylva__grid_vacate(&g, v);
  CHECK_INT(sylva__grid_occupant(&g, v), -1);
  CHECK_INT(sylva__grid_occupy(&g, v, 8), 0);
  sylva__grid_free(&g);
}

/* The occupancy table of voxel v's chunk (NULL: none). */
static const sylva__occ *occ_of(const sylva__grid *g, const int v[3]) {
  size_t cx = (size_t)(v[0] >> 4), cy = (size_t)(v[1] >> 4), cz = (size_t)(v[2] >> 4);
  return g->occ[(cz * (size_t)g->c[1] + cy) * (size_t)g->c[0] + cx];
}

/* A chunk's occupancy table lives while a node is in it: made with the first,
 * grown as nodes come, freed with the last (not before, whatever leaves first), and
 * another chunk's table is left alone. */
static void test_occupancy_freed(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {2, 2, 2};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  int a[40][3], b[3] = {35, 35, 35};
  for (int i = 0; i < 40; i++) { /* 40 voxels of chunk (0, 0, 0): the table grows twice */
    a[i][0] = i % 16;
    a[i][1] = (i * 7) % 16;
    a[i][2] = i / 16;
    CHECK_INT(sylva__grid_occupy(&g, a[i], 3), 0);
  }
  CHECK_INT(sylva__grid_occupy(&g, a[0], 3), 0); /* a second node of stem 3 in a voxel */
  CHECK_INT(sylva__grid_occupy(&g, b, 4), 0);
  CHECK(occ_of(&g, a[0]) != NULL && occ_of(&g, b) != NULL && occ_of(&g, a[0]) != occ_of(&g, b));
  CHECK_INT(g.occ_count, 2);
  CHECK(occ_of(&g, a[0])->cap >= 64);
  for (int i = 39; i >= 0; i--) sylva__grid_vacate(&g, a[i]);
  CHECK(occ_of(&g, a[0]) != NULL); /* voxel a[0] still holds a node */
  CHECK_INT(sylva__grid_occupant(&g, a[0]), 3);
  CHECK_INT(sylva__grid_occupant(&g, a[1]), -1);
  sylva__grid_vacate(&g, a[0]);
  CHECK(occ_of(&g, a[0]) == NULL); /* the last node left: the table is gone */
  CHECK_INT(g.occ_count, 1);
  CHECK(occ_of(&g, b) != NULL);
  CHECK_INT(sylva__grid_occupant(&g, b), 4);
  sylva__grid_vacate(&g, b);
  CHECK(occ_of(&g, b) == NULL);
  CHECK_INT(g.occ_count, 0);
  CHECK_INT(g.occ_bytes, 0);
  CHECK_INT(sylva__grid_occupy(&g, a[5], 9), 0); /* a table again for a new node */
  CHECK_INT(sylva__grid_occupant(&g, a[5]), 9);
  sylva__grid_free(&g);
}

/* What the grid reports of its memory falls back as nodes leave and their chunks'
 * tables empty; the shade of nodes stamped and unstamped is zero everywhere again
 * (the chunks it made stay: they live as long as the grid). */
static void test_memory_falls(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {3, 3, 3};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  size_t empty = sylva__grid_bytes(&g);
  enum { N = 200 };
  int vox[N][3];
  int64_t w[12];
  for (int q = 1; q <= 12; q++) w[q - 1] = fixed(pow(1.9, -q));
  sylva__rng r;
  sylva__rng_seed(&r, 5);
  int placed = 0;
  for (int i = 0; i < N; i++) {
    for (int a = 0; a < 3; a++) vox[placed][a] = (int)sylva__rng_below(&r, (uint32_t)g.n[a]);
    int rc = sylva__grid_occupy(&g, vox[placed], i % 3); /* three stems */
    if (rc == SYLVA_EOCCUPIED) continue; /* another stem's voxel */
    CHECK_INT(rc, 0);
    placed++;
  }
  CHECK(placed > N / 2);
  size_t occupied = sylva__grid_bytes(&g);
  CHECK(occupied > empty);
  for (int i = 0; i < placed; i++) CHECK_INT(stamp(&g, vox[i], 12, w, +1), 0);
  size_t shaded = sylva__grid_bytes(&g);
  CHECK(shaded > occupied);
  /* the first half leaves: the bytes fall as whole tables go, never rise */
  size_t before = shaded;
  for (int i = 0; i < placed / 2; i++) {
    CHECK_INT(stamp(&g, vox[i], 12, w, -1), 0);
    sylva__grid_vacate(&g, vox[i]);
    size_t now = sylva__grid_bytes(&g);
    CHECK(now <= before);
    before = now;
  }
  for (int i = placed / 2; i < placed; i++) {
    CHECK_INT(stamp(&g, vox[i], 12, w, -1), 0);
    sylva__grid_vacate(&g, vox[i]);
  }
  CHECK_INT(g.occ_count, 0);
  CHECK_INT(g.occ_bytes, 0);
  CHECK_INT(sylva__grid_bytes(&g), shaded - (occupied - empty)); /* every table's bytes back */
  CHECK_INT(shaded_voxels(&g), 0);
  sylva__grid_free(&g);
}

/* A batch on several threads adds the shade the stamps give one by one, and taking
 * it away leaves none: on 1 thread (one part), 2 (8 parts over the 10 chunk
 * columns, of one or two each) and 8 (a part per column), with the scratch each asks
 * for, and stamps wide enough to span up to four columns, at the grid's edges too. */
static void test_stamp_many(void) {
  double mn[3] = {0, 0, 0}, mx[3] = {8, 1.5, 2.5};
  enum { N = 150 };
  sylva__pyramid pyr[3];
  for (int k = 0; k < 3; k++) { /* half-widths up to 6, 15 and 24 voxels */
    sylva__pyramid *p = &pyr[k];
    p->depth = 12 + 4 * k;
    p->column = fixed(0.001 * (k + 1));
    for (int q = 1; q <= p->depth; q++) {
      p->w[q - 1] = fixed(pow(1.8 + 0.1 * k, -q));
      p->half[q - 1] = q * (k + 1) / 2;
    }
  }
  sylva__stamp items[N];
  sylva__rng r;
  sylva__rng_seed(&r, 17);
  sylva__grid one;
  CHECK_INT(sylva__grid_init(&one, mn, mx, 0.05), 0);
  for (int i = 0; i < N; i++) {
    for (int a = 0; a < 3; a++) items[i].v[a] = (int)sylva__rng_below(&r, (uint32_t)one.n[a]);
    if (i % 10 == 0) items[i].v[0] = i % 20 ? 0 : one.n[0] - 1; /* at either edge */
    items[i].p = &pyr[i % 3];
    CHECK_INT(sylva__grid_stamp(&one, items[i].v, items[i].p, +1), 0);
  }
  CHECK_INT(one.c[0], 10);
  const int threads[] = {1, 2, 8};
  for (int t = 0; t < 3; t++) {
    sylva__pool *pool = NULL;
    CHECK_INT(sylva__pool_create(threads[t], &pool), 0);
    size_t need = sylva__grid_stamp_scratch(&one, pool, items, N);
    /* the parts' firsts and every item once at least, some in several parts */
    CHECK(threads[t] == 1 ? need == 0 : need > (threads[t] == 2 ? 9 : 11) + (size_t)N);
    size_t *scratch = need ? malloc(need * sizeof *scratch) : NULL;
    sylva__grid g;
    CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
    CHECK_INT(sylva__grid_stamp_many(&g, pool, items, N, +1, scratch), 0);
    CHECK(grids_equal(&g, &one));
    CHECK_INT(sylva__grid_stamp_many(&g, pool, items, N, -1, scratch), 0);
    CHECK_INT(shaded_voxels(&g), 0);
    free(scratch);
    sylva__grid_free(&g);
    sylva__pool_destroy(pool);
  }
  sylva__grid_free(&one);
}

/* The room reserved ahead of a removal holds what any batch asks for: a stamp of
 * every half-width up to the bound's, at every x of the grid (its edges too), on
 * parts of one to four columns (10 or 26 columns over 8, 10, 12 or 26 parts), takes
 * no more than its share of sylva__grid_stamp_scratch_max. */
static void test_stamp_scratch_max(void) {
  const double widths[] = {8.0, 20.8};
  const int threads[] = {2, 3, 8};
  sylva__pyramid p = {.depth = 1, .w = {1}};
  for (int wi = 0; wi < 2; wi++) {
    double mn[3] = {0, 0, 0}, mx[3] = {widths[wi], 0.8, 0.8};
    sylva__grid g;
    CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
    CHECK_INT(g.c[0], wi ? 26 : 10);
    for (int t = 0; t < 3; t++) {
      sylva__pool *pool = NULL;
      CHECK_INT(sylva__pool_create(threads[t], &pool), 0);
      for (int half = 0; half <= 50; half++) {
        size_t max1 = sylva__grid_stamp_scratch_max(&g, pool, 1, half);
        bool fits = true, tight = false;
        for (int h = 0; h <= half; h++) {
          p.half[0] = h;
          for (int x = 0; x < g.n[0]; x++) {
            sylva__stamp it = {{x, 5, 5}, &p};
            size_t need = sylva__grid_stamp_scratch(&g, pool, &it, 1);
            fits &= need <= max1;
            tight |= need == max1;
          }
        }
        CHECK(fits);
        /* and some stamp needs it all, but where parts of one and two columns mix
         * (8 parts over 10 columns) under stamps of six columns or more */
        CHECK(tight || (wi == 0 && threads[t] == 2 && half > 32));
        /* n stamps: the parts' firsts once, each stamp's share n times */
        size_t per = max1 - sylva__grid_stamp_scratch_max(&g, pool, 0, half);
        CHECK_INT(sylva__grid_stamp_scratch_max(&g, pool, 7, half), max1 + 6 * per);
      }
      sylva__pool_destroy(pool);
    }
    sylva__grid_free(&g);
  }
}

static void test_obstacles(void) {
  sylva__grid g;
  double mn[3] = {-1, -1, 0}, mx[3] = {1, 1, 2};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  double bmn[3] = {0, 0, 1.0}, bmx[3] = {0.5, 0.5, 1.05}; /* a board thinner than a voxel */
  int id = sylva__grid_add_obstacle(&g, "board", bmn, bmx);
  CHECK(id >= 0);
  CHECK_INT(sylva__grid_add_obstacle(&g, "board", bmn, bmx), SYLVA_EINVAL); /* duplicate */
  CHECK_INT(sylva__grid_find_obstacle(&g, "board"), id);
  int in[3] = {12, 12, 10}, under[3] = {12, 12, 0}, beside[3] = {8, 12, 5}, above[3] = {12, 12, 11};
  CHECK(sylva__grid_blocked(&g, in));
  CHECK(!sylva__grid_blocked(&g, under));
  CHECK_NEAR(sylva__grid_light(&g, in), 0.0, 0.0);
  CHECK_NEAR(sylva__grid_light(&g, under), 0.0, 0.0); /* full shadow below */
  CHECK_NEAR(sylva__grid_light(&g, beside), 1.0, 0.0);
  CHECK_NEAR(sylva__grid_light(&g, above), 1.0, 0.0);
  CHECK_INT(sylva__grid_remove_obstacle(&g, id), 0);
  CHECK_NEAR(sylva__grid_light(&g, under), 1.0, 0.0);
  CHECK_INT(sylva__grid_remove_obstacle(&g, id), SYLVA_ENOTFOUND);
  sylva__grid_free(&g);
}

static void test_sparse_site(void) {
  /* 50 m x 50 m x 25 m at 5 cm: 500 million voxels */
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {50, 50, 25};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  CHECK_INT((long long)g.n[0] * g.n[1] * g.n[2], 500000000LL);
  size_t empty = sylva__grid_bytes(&g);
  CHECK(empty < 4u << 20); /* the chunk table only */
  int64_t w[20];
  for (int q = 1; q <= 20; q++) w[q - 1] = fixed(pow(2.0, -q));
  int v[3] = {500, 500, 400};
  CHECK_INT(stamp(&g, v, 20, w, +1), 0);
  CHECK_INT(sylva__grid_occupy(&g, v, 0), 0);
  size_t one = sylva__grid_bytes(&g) - empty;
  CHECK(one < 2u << 20); /* a handful of chunks, not the column to the ground */
  CHECK_NEAR(sylva__grid_light(&g, (int[3]){500, 500, 3}), 1.0 - pow(2.0, -20), 1e-9);
  printf("sparse site: %zu bytes empty, %zu more for one node\n", empty, one);
  sylva__grid_free(&g);
  /* a box too large for the voxel edge is refused */
  double big[3] = {10000, 10000, 1000};
  CHECK_INT(sylva__grid_init(&g, mn, big, 0.01), SYLVA_ETOOBIG);
}

/* The calibrated shape: half-width q (shade_spread 1) and a column value of its own. */
static void test_wide_pyramid(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {2, 2, 2};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  sylva__pyramid p = {.depth = 3, .column = fixed(0.002)};
  for (int q = 1; q <= 3; q++) {
    p.w[q - 1] = fixed(pow(2.0, -q));
    p.half[q - 1] = q;
  }
  int v[3] = {20, 20, 30};
  CHECK_INT(sylva__grid_stamp(&g, v, &p, +1), 0);
#define S(x, y, z) sylva__grid_shade_raw(&g, (int[3]){x, y, z})
  CHECK_INT(S(21, 19, 29), p.w[0]); /* q = 1 already reaches one voxel sideways */
  CHECK_INT(S(22, 20, 29), 0);
  CHECK_INT(S(23, 17, 27), p.w[2]); /* q = 3: half-width 3 */
  CHECK_INT(S(24, 20, 27), 0);
  CHECK_INT(S(17, 23, 26), p.column); /* the column: the base's 7 x 7 footprint */
  CHECK_INT(S(20, 20, 0), p.column);
  CHECK_INT(S(24, 20, 10), 0);
  CHECK_INT(sylva__grid_stamp(&g, v, &p, -1), 0);
  CHECK_INT(S(17, 23, 26), 0);
  CHECK_INT(S(21, 19, 29), 0);
#undef S
  sylva__grid_free(&g);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(wide_pyramid), CHECK_TEST(pyramid_and_column), CHECK_TEST(against_definition),
      CHECK_TEST(exact_removal), CHECK_TEST(occupancy), CHECK_TEST(occupancy_freed),
      CHECK_TEST(memory_falls), CHECK_TEST(stamp_many), CHECK_TEST(stamp_scratch_max),
      CHECK_TEST(obstacles),
      CHECK_TEST(sparse_site)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("grid");
}
