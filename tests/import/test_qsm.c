/* The readers of libsylva-import (server/import/qsm.h): every ITSMe TreeQSM file
 * (data/, MIT, see data/LICENSE.md) read and checked against its own treedata;
 * .mat -> text -> read and .mat -> CSV -> read exactly; TreeQSM's rounded text,
 * its older 15 columns, SimpleForest's CSV, sylva.skeleton/1 and MATLAB 7.3; and
 * bad input, each with a message naming what and where. */
#include <dirent.h>
#include <matio.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <unistd.h>

#include "../check.h"
#include "qsm.h"
#include "sylva/status.h"

#ifndef QSM_DATA
#error "QSM_DATA: the directory of the ITSMe files"
#endif

static char tmpdir[64];

/* A path in the data directory or the temporary one (a few at a time). */
static const char *data_path(const char *name) {
  static char buf[16][512];
  static int k;
  k = (k + 1) % 16;
  snprintf(buf[k], sizeof buf[k], "%s/%s", QSM_DATA, name);
  return buf[k];
}

static const char *tmp_path(const char *name) {
  static char buf[16][512];
  static int k;
  k = (k + 1) % 16;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

static void write_bytes(const char *path, const void *data, size_t len) {
  FILE *f = fopen(path, "wb");
  if (!f) {
    fprintf(stderr, "cannot write %s\n", path);
    exit(1);
  }
  if (len) CHECK(fwrite(data, 1, len, f) == len);
  CHECK(fclose(f) == 0);
}

static void write_text(const char *path, const char *text) {
  write_bytes(path, text, strlen(text));
}

static char *read_bytes(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "cannot read %s\n", path);
    exit(1);
  }
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *buf = malloc((size_t)n + 1);
  if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) exit(1);
  fclose(f);
  *len = (size_t)n;
  return buf;
}

static sylva_qsm must_read(const char *path, sylva_qsm_format f, int model) {
  sylva_qsm q;
  char err[512];
  int rc = sylva_qsm_read(path, f, model, &q, err, sizeof err);
  if (rc) fprintf(stderr, "%s: %s\n", path, err);
  CHECK_INT(rc, SYLVA_OK);
  return q;
}

/* Reading path fails with status, an empty q, and a message holding each word
 * (a NULL-terminated list). */
static void expect_fail(const char *path, sylva_qsm_format f, int model, int status, ...) {
  sylva_qsm q;
  char err[512];
  memset(&q, 0x5a, sizeof q);
  int rc = sylva_qsm_read(path, f, model, &q, err, sizeof err);
  printf("  bad: %s\n", err);
  CHECK_INT(rc, status);
  CHECK(q.cyl == NULL && q.count == 0);
  va_list ap;
  va_start(ap, status);
  for (const char *w; (w = va_arg(ap, const char *));)
    if (!strstr(err, w)) {
      check_failed++;
      fprintf(stderr, "message '%s' lacks '%s'\n", err, w);
    }
  va_end(ap);
  sylva_qsm_free(&q);
}

/* The number of cylinders where a and b differ in the fields given; the first is told. */
static size_t differences(const sylva_qsm *a, const sylva_qsm *b, bool branches, double tol) {
  if (a->count != b->count) {
    fprintf(stderr, "%zu cylinders != %zu\n", a->count, b->count);
    return a->count > b->count ? a->count : b->count;
  }
  size_t bad = 0;
  for (size_t i = 0; i < a->count; i++) {
    const sylva_qsm_cylinder *x = &a->cyl[i], *y = &b->cyl[i];
    bool same = fabs(x->radius - y->radius) <= tol && fabs(x->length - y->length) <= tol &&
                x->parent == y->parent;
    for (int k = 0; k < 3; k++)
      same = same && fabs(x->start[k] - y->start[k]) <= tol && fabs(x->axis[k] - y->axis[k]) <= tol;
    if (branches) same = same && x->branch == y->branch && x->branch_order == y->branch_order;
    if (!same && bad++ == 0)
      fprintf(stderr,
              "cylinder %zu: r %.17g/%.17g l %.17g/%.17g start %.17g/%.17g axis %.17g/%.17g "
              "parent %d/%d branch %d/%d order %d/%d\n",
              i + 1, x->radius, y->radius, x->length, y->length, x->start[2], y->start[2],
              x->axis[2], y->axis[2], x->parent, y->parent, x->branch, y->branch, x->branch_order,
              y->branch_order);
  }
  return bad;
}

/* ---- The ITSMe files ---- */

typedef struct itsme_file {
  const char *name;
  const char *version; /* TreeQSM version, from rundata.inputs or the layout */
  int models;
  size_t cylinders; /* of the first model */
} itsme_file;

static const itsme_file itsme[] = {
    {"buttressed_trees_buttressed_tree_2_qsm_1.mat", "2.4.0 QSM", 1, 169},
    {"non_buttressed_trees_single_qsm_tree_1_qsm.mat", "2.4.0 QSM", 1, 66},
    {"non_buttressed_trees_single_qsm_tree_2_qsm.mat", "2.4.0 QSM", 1, 106},
    {"qsms_qsm_tree_v200.mat", "2.0 flat", 1, 115},
    {"qsms_qsm_tree_v230.mat", "2.3 QSMs", 1, 88},
    {"qsms_qsm_tree_v240.mat", "2.4.0 QSM", 1, 3791},
    {"qsms_qsm_tree_v240_notria.mat", "2.4.0 QSM", 1, 66},
    {"qsms_qsm_trunk.mat", "2.4.0 QSM", 1, 48},
    {"qsms_qsms_tree_v240_notria.mat", "2.4.0 QSMs", 10, 66},
};
enum { ITSME_FILES = sizeof itsme / sizeof itsme[0] };

static double end_z(const sylva_qsm_cylinder *c) { return c->start[2] + c->length * c->axis[2]; }

/* Distance from point p to the axis segment of cylinder c. */
static double to_segment(const double p[3], const sylva_qsm_cylinder *c) {
  double t = 0;
  for (int k = 0; k < 3; k++) t += (p[k] - c->start[k]) * c->axis[k];
  t = fmax(0, fmin(c->length, t));
  double d2 = 0;
  for (int k = 0; k < 3; k++) {
    double e = p[k] - (c->start[k] + t * c->axis[k]);
    d2 += e * e;
  }
  return sqrt(d2);
}

/* What a model looks like: roots, parents listed after their children, and how far
 * each cylinder starts from its parent's end (a continuation) or axis (a branch). */
static void describe(const sylva_qsm *q) {
  size_t roots = 0, late = 0, orphan_branches = 0;
  double cont_gap = 0, branch_gap = 0, branch_gap_end = 0;
  int max_order = 0, max_branch = 0;
  for (size_t i = 0; i < q->count; i++) {
    const sylva_qsm_cylinder *c = &q->cyl[i];
    if (c->branch_order > max_order) max_order = c->branch_order;
    if (c->branch > max_branch) max_branch = c->branch;
    if (c->parent < 0) {
      roots++;
      continue;
    }
    if ((size_t)c->parent > i) late++;
    const sylva_qsm_cylinder *p = &q->cyl[c->parent];
    double end[3], d2 = 0;
    for (int k = 0; k < 3; k++) {
      end[k] = p->start[k] + p->length * p->axis[k];
      d2 += (c->start[k] - end[k]) * (c->start[k] - end[k]);
    }
    if (p->branch == c->branch)
      cont_gap = fmax(cont_gap, sqrt(d2));
    else {
      branch_gap = fmax(branch_gap, to_segment(c->start, p));
      branch_gap_end = fmax(branch_gap_end, sqrt(d2));
      if (c->branch_order != p->branch_order + 1) orphan_branches++;
    }
  }
  printf("    roots %zu, parents after their child %zu, branches %d, max order %d\n", roots, late,
         max_branch, max_order);
  printf(
      "    largest gap: continuation start to parent end %.4f m; branch start to parent "
      "axis %.4f m (to parent end %.4f m); branch order not parent's + 1: %zu\n",
      cont_gap, branch_gap, branch_gap_end, orphan_branches);
}

static void test_itsme(void) {
  for (size_t f = 0; f < ITSME_FILES; f++) {
    const itsme_file *it = &itsme[f];
    const char *path = data_path(it->name);
    CHECK_INT(sylva_qsm_sniff(path), SYLVA_QSM_MAT);
    for (int m = 1; m <= it->models; m++) {
      sylva_qsm q = must_read(path, SYLVA_QSM_UNKNOWN, m == 1 ? 0 : m);
      CHECK_INT(q.models, it->models);
      if (m == 1) CHECK_INT(q.count, it->cylinders);
      const sylva_qsm_treedata *t = &q.treedata;
      double vol = 0, top = -INFINITY, bottom = INFINITY;
      for (size_t i = 0; i < q.count; i++) {
        const sylva_qsm_cylinder *c = &q.cyl[i];
        vol += 3.14159265358979323846 * c->radius * c->radius * c->length;
        top = fmax(top, fmax(c->start[2], end_z(c)));
        bottom = fmin(bottom, c->start[2]);
        double n =
            sqrt(c->axis[0] * c->axis[0] + c->axis[1] * c->axis[1] + c->axis[2] * c->axis[2]);
        if (fabs(n - 1) > 1e-12) {
          check_failed++;
          fprintf(stderr, "%s: cylinder %zu: axis length %.17g\n", it->name, i + 1, n);
        }
      }
      printf("%s (TreeQSM %s) model %d of %d: %zu cylinders", it->name, it->version, m, q.models,
             q.count);
      if (q.has_treedata)
        printf(
            "; treedata: height %.4g m, DBH %.4g m, volume %.6g L, length %.6g m, branches %g, "
            "max order %g\n",
            t->height, t->dbh, t->total_volume, t->total_length, t->branches, t->max_order);
      else
        printf("; no treedata\n");
      printf("    cylinders: top - bottom %.4f m, sum pi r^2 l %.6g L\n", top - bottom, vol * 1000);
      if (m == 1) describe(&q);
      CHECK(q.has_treedata);
      if (q.has_treedata) {
        CHECK(isfinite(t->height) && isfinite(t->total_volume) && isfinite(t->dbh));
        CHECK_NEAR(top - bottom, t->height, 0.02 * t->height);
        CHECK_NEAR(vol, t->total_volume / 1000, 0.10 * t->total_volume / 1000);
        CHECK(t->dbh > 0 && t->dbh < 3);
      }
      sylva_qsm_free(&q);
      CHECK(q.cyl == NULL && q.count == 0);
    }
  }
  /* The 2.0 file's TreeData is a vector of three-figure values, DBH in cm; 2.3
   * has no TotalLength. */
  sylva_qsm q = must_read(data_path("qsms_qsm_tree_v200.mat"), SYLVA_QSM_MAT, 1);
  CHECK_NEAR(q.treedata.total_volume, 8.04, 1e-12);
  CHECK_NEAR(q.treedata.height, 5.42, 1e-12);
  CHECK_NEAR(q.treedata.dbh, 0.038, 1e-12);
  CHECK_NEAR(q.treedata.branches, 22, 0);
  CHECK_NEAR(q.treedata.max_order, 3, 0);
  CHECK(isnan(q.treedata.total_length));
  int max_order = 0;
  for (size_t i = 0; i < q.count; i++)
    if (q.cyl[i].branch_order > max_order) max_order = q.cyl[i].branch_order;
  CHECK_INT(max_order, 3);
  CHECK_INT(q.cyl[0].parent, -1);
  CHECK_INT(q.cyl[1].parent, 0);
  sylva_qsm_free(&q);
  q = must_read(data_path("qsms_qsm_tree_v230.mat"), SYLVA_QSM_MAT, 0);
  CHECK(isnan(q.treedata.total_length));
  CHECK_NEAR(q.treedata.branches, 2, 0);
  sylva_qsm_free(&q);
  q = must_read(data_path("qsms_qsm_tree_v240.mat"), SYLVA_QSM_MAT, 0);
  CHECK_NEAR(q.treedata.total_length, 561.561, 1e-3);
  CHECK_NEAR(q.treedata.max_order, 6, 0);
  sylva_qsm_free(&q);
  /* The ten models of one tree differ. */
  sylva_qsm a = must_read(data_path("qsms_qsms_tree_v240_notria.mat"), SYLVA_QSM_MAT, 1);
  sylva_qsm b = must_read(data_path("qsms_qsms_tree_v240_notria.mat"), SYLVA_QSM_MAT, 2);
  CHECK(a.count != b.count || a.cyl[0].radius != b.cyl[0].radius);
  CHECK_INT(b.count, 73);
  sylva_qsm_free(&a);
  sylva_qsm_free(&b);
}

/* ---- Round trips ---- */

static void test_round_trip(void) {
  for (size_t f = 0; f < ITSME_FILES; f++) {
    const itsme_file *it = &itsme[f];
    for (int m = 1; m <= it->models; m += 4) {
      sylva_qsm q = must_read(data_path(it->name), SYLVA_QSM_MAT, m);
      const char *txt = tmp_path("round.txt"), *csv = tmp_path("round.csv");
      CHECK_INT(sylva_qsm_write_text(&q, txt), SYLVA_OK);
      CHECK_INT(sylva_qsm_write_csv(&q, csv), SYLVA_OK);
      CHECK_INT(sylva_qsm_sniff(txt), SYLVA_QSM_TEXT);
      CHECK_INT(sylva_qsm_sniff(csv), SYLVA_QSM_CSV);
      sylva_qsm t = must_read(txt, SYLVA_QSM_UNKNOWN, 0);
      sylva_qsm c = must_read(csv, SYLVA_QSM_UNKNOWN, 0);
      /* Exactly: %.17g, and axes already of unit length are left alone. */
      CHECK_INT(differences(&q, &t, true, 0), 0);
      CHECK_INT(differences(&q, &c, true, 0), 0);
      CHECK(!t.has_treedata && isnan(t.treedata.height));
      CHECK_INT(t.models, 1);
      /* Twice over: the written files are the same bytes. */
      const char *txt2 = tmp_path("round2.txt");
      CHECK_INT(sylva_qsm_write_text(&t, txt2), SYLVA_OK);
      size_t n1, n2;
      char *b1 = read_bytes(txt, &n1), *b2 = read_bytes(txt2, &n2);
      CHECK(n1 == n2 && memcmp(b1, b2, n1) == 0);
      free(b1);
      free(b2);
      sylva_qsm_free(&q);
      sylva_qsm_free(&t);
      sylva_qsm_free(&c);
    }
  }
}

/* The written text has TreeQSM's extension and position-in-branch columns. */
static void test_text_columns(void) {
  sylva_qsm q = must_read(data_path("qsms_qsm_tree_v240_notria.mat"), SYLVA_QSM_MAT, 0);
  const char *txt = tmp_path("columns.txt");
  CHECK_INT(sylva_qsm_write_text(&q, txt), SYLVA_OK);
  FILE *f = fopen(txt, "r");
  char line[4096];
  CHECK(fgets(line, sizeof line, f) != NULL);
  CHECK(strncmp(line, "radius (m)\tlength (m)\tstart_point", 33) == 0);
  /* Row 1: the stem's first cylinder, extended by cylinder 2, first in branch 1. */
  CHECK(fgets(line, sizeof line, f) != NULL);
  double v[17];
  int n = 0;
  char *save = NULL;
  for (char *t = strtok_r(line, "\t\n", &save); t && n < 17; t = strtok_r(NULL, "\t\n", &save))
    v[n++] = strtod(t, NULL);
  CHECK_INT(n, 17);
  CHECK_NEAR(v[8], 0, 0);  /* parent */
  CHECK_NEAR(v[9], 2, 0);  /* extension */
  CHECK_NEAR(v[10], 1, 0); /* branch */
  CHECK_NEAR(v[11], 0, 0); /* order */
  CHECK_NEAR(v[12], 1, 0); /* position in branch */
  CHECK_NEAR(v[16], q.cyl[0].radius, 0);
  fclose(f);
  sylva_qsm_free(&q);
}

/* TreeQSM's own text: rounded to 4 decimals, %g, a header row; and its older form,
 * 15 columns without a header, whitespace-separated. */
static void test_treeqsm_text(void) {
  sylva_qsm q =
      must_read(data_path("buttressed_trees_buttressed_tree_2_qsm_1.mat"), SYLVA_QSM_MAT, 0);
  const char *p17 = tmp_path("cylinder_tree.txt"), *p15 = tmp_path("cyl_data_tree.txt");
  FILE *f17 = fopen(p17, "w"), *f15 = fopen(p15, "w");
  fputs(
      "radius (m)\tlength (m)\tstart_point\taxis_direction\tparent\textension\tbranch\t"
      "branch_order\tposition_in_branch\tmad\tSurfCov\tadded\tUnmodRadius (m)\n",
      f17);
  for (size_t i = 0; i < q.count; i++) {
    const sylva_qsm_cylinder *c = &q.cyl[i];
    double r[8] = {c->radius,   c->length,  c->start[0], c->start[1],
                   c->start[2], c->axis[0], c->axis[1],  c->axis[2]};
    for (int k = 0; k < 8; k++) r[k] = round(10000 * r[k]) / 10000;
    fprintf(f17, "%g\t%g\t%g\t%g\t%g\t%g\t%g\t%g\t%d\t0\t%d\t%d\t1\t0.0021\t0.85\t0\t%g\r\n", r[0],
            r[1], r[2], r[3], r[4], r[5], r[6], r[7], c->parent + 1, c->branch, c->branch_order,
            r[0]);
    fprintf(f15, "%.17g %.17g  %.17g %.17g %.17g\t%.17g %.17g %.17g %d 0 %d %d 1 0 %.17g\n",
            c->radius, c->length, c->start[0], c->start[1], c->start[2], c->axis[0], c->axis[1],
            c->axis[2], c->parent + 1, c->branch, c->branch_order, c->radius);
  }
  fputs("\n\n", f15); /* trailing blank lines */
  fclose(f17);
  fclose(f15);
  sylva_qsm t17 = must_read(p17, SYLVA_QSM_UNKNOWN, 0);
  sylva_qsm t15 = must_read(p15, SYLVA_QSM_TEXT, 1);
  /* Rounded axes come back of unit length, within the rounding of the file (%g
   * keeps six figures: 121.887 for a y of 121.88749). */
  CHECK_INT(differences(&q, &t17, true, 6e-4), 0);
  for (size_t i = 0; i < t17.count; i++) {
    const double *a = t17.cyl[i].axis;
    CHECK_NEAR(a[0] * a[0] + a[1] * a[1] + a[2] * a[2], 1, 1e-12);
  }
  CHECK_INT(differences(&q, &t15, true, 0), 0);
  sylva_qsm_free(&q);
  sylva_qsm_free(&t17);
  sylva_qsm_free(&t15);
}

/* SimpleForest's CSV: names with leading blanks, six decimals, more columns than
 * needed, rows in any order, IDs from 0 and -1 for the root's parent. */
static void test_simpleforest_csv(void) {
  sylva_qsm q =
      must_read(data_path("non_buttressed_trees_single_qsm_tree_2_qsm.mat"), SYLVA_QSM_MAT, 0);
  const char *path = tmp_path("simpleforest.csv");
  FILE *f = fopen(path, "w");
  fputs(
      " ID, parentID, startX, startY, startZ, endX, endY, endZ, radius, length, growthLength, "
      "averagePointDistance,segmentID, parentSegmentID, branchOrder, reverseBranchOrder, "
      "branchID\n",
      f);
  /* Rows from last to first; ID k is cylinder k. */
  for (size_t r = 0; r < q.count; r++) {
    size_t i = q.count - 1 - r;
    const sylva_qsm_cylinder *c = &q.cyl[i];
    double e[3];
    for (int k = 0; k < 3; k++) e[k] = c->start[k] + c->length * c->axis[k];
    fprintf(f, "%zu,%d,%f,%f,%f,%f,%f,%f,%f,%f,1.5,0.003,0,-1,%d,4,%d\n", i, c->parent, c->start[0],
            c->start[1], c->start[2], e[0], e[1], e[2], c->radius, c->length, c->branch_order,
            c->branch);
  }
  fclose(f);
  CHECK_INT(sylva_qsm_sniff(path), SYLVA_QSM_CSV);
  sylva_qsm s = must_read(path, SYLVA_QSM_UNKNOWN, 0);
  CHECK_INT(s.count, q.count);
  size_t bad = 0;
  for (size_t r = 0; r < s.count && r < q.count; r++) {
    size_t i = q.count - 1 - r;
    const sylva_qsm_cylinder *a = &q.cyl[i], *b = &s.cyl[r];
    int parent_row = a->parent < 0 ? -1 : (int)(q.count - 1) - a->parent;
    bool same = b->parent == parent_row && fabs(a->radius - b->radius) < 1e-6 &&
                fabs(a->length - b->length) < 1e-5 && b->branch == a->branch &&
                b->branch_order == a->branch_order;
    for (int k = 0; k < 3; k++)
      same = same && fabs(a->start[k] - b->start[k]) < 1e-6 && fabs(a->axis[k] - b->axis[k]) < 1e-4;
    if (!same) bad++;
  }
  CHECK_INT(bad, 0);
  sylva_qsm_free(&q);
  sylva_qsm_free(&s);
}

/* ---- sylva.skeleton/1 ---- */

static const char skeleton[] =
    "{\"format\":\"sylva.skeleton/1\",\"iteration\":3,\"voxel\":0.05,"
    "\"world\":{\"min\":[-2,-2,0],\"max\":[2,2,4]},"
    "\"obstacles\":[{\"id\":\"wall\",\"kind\":\"box\",\"min\":[0.8,-2,0],\"max\":[1,2,2]}],"
    "\"plants\":[{\"id\":\"t1\",\"stems\":[{\"root\":[0,0,0],\"nodes\":["
    "[0,-1,0,0,0,0.012,0],[1,0,0,0,0.1,0.011,0],[2,1,0,0,0.2,0.01,0],"
    "[3,2,0.0124,-0.0081,0.2989,0.008,1],[4,1,0.05,0,0.1,0.005,2]]}]},"
    "{\"id\":\"t2\",\"stems\":[{\"root\":[1,1,0],\"nodes\":[[10,-1,1,1,0,0.02,0],[12,11,1,1,0.2,0."
    "01,0],"
    "[11,10,1,1,0.1,0.015,0]]},{\"root\":[1.5,1,0],\"nodes\":[[20,-1,1.5,1,0,0.02,0],"
    "[21,20,1.5,1,0.3,0.02,0]]}]}]}\n";

static void test_skeleton(void) {
  const char *path = tmp_path("skeleton.json");
  write_text(path, skeleton);
  CHECK_INT(sylva_qsm_sniff(path), SYLVA_QSM_SKELETON);
  sylva_qsm q = must_read(path, SYLVA_QSM_UNKNOWN, 0);
  CHECK_INT(q.models, 2);
  CHECK_INT(q.count, 4);
  if (q.count == 4) {
    CHECK_INT(q.cyl[0].parent, -1); /* node 1: its parent is the root node */
    CHECK_INT(q.cyl[1].parent, 0);
    CHECK_INT(q.cyl[2].parent, 1);
    CHECK_INT(q.cyl[3].parent, 0);
    CHECK_NEAR(q.cyl[0].length, 0.1, 1e-15);
    CHECK_NEAR(q.cyl[0].axis[2], 1, 0);
    CHECK_NEAR(q.cyl[0].radius, 0.011, 0);
    CHECK_NEAR(q.cyl[2].start[2], 0.2, 0);
    CHECK_NEAR(q.cyl[2].radius, 0.008, 0);
    CHECK_NEAR(q.cyl[3].axis[0], 1, 0);
    CHECK_NEAR(q.cyl[3].length, 0.05, 1e-15);
  }
  CHECK(!q.has_treedata);
  sylva_qsm_free(&q);
  /* Plant 2: children listed before their parents, two stems (two roots). */
  q = must_read(path, SYLVA_QSM_SKELETON, 2);
  CHECK_INT(q.count, 3);
  if (q.count == 3) {
    CHECK_INT(q.cyl[0].parent, 1); /* node 12 under node 11 */
    CHECK_INT(q.cyl[1].parent, -1);
    CHECK_INT(q.cyl[2].parent, -1);
    CHECK_NEAR(q.cyl[2].length, 0.3, 1e-15);
  }
  sylva_qsm_free(&q);
  expect_fail(path, SYLVA_QSM_UNKNOWN, 3, SYLVA_ERANGE, "no model 3", "2 plants", NULL);
  const char *bad = tmp_path("bad_skeleton.json");
  write_text(bad,
             "{\"format\":\"sylva.skeleton/1\",\"plants\":[{\"id\":\"t1\",\"stems\":[{\"root\":"
             "[0,0,0],\"nodes\":[[0,-1,0,0,0,0.01,0],[1,7,0,0,1,0.01,0]]}]}]}");
  expect_fail(bad, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "plant 't1', node 1", "parent 7", NULL);
  write_text(bad,
             "{\"format\":\"sylva.skeleton/1\",\"plants\":[{\"id\":\"t1\",\"stems\":[{\"root\":"
             "[0,0,0],\"nodes\":[[0,-1,0,0,0,0.01,0],[1,0,0,0,1,0,0]]}]}]}");
  expect_fail(bad, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "node 1", "radius 0 is not above 0", NULL);
  write_text(bad, "{\"format\":\"sylva.skeleton/1\",\"plants\":[]}");
  expect_fail(bad, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no plants", NULL);
  write_text(bad, "{\"format\":\"sylva.scenario/1\",\"plants\":[]}");
  expect_fail(bad, SYLVA_QSM_SKELETON, 0, SYLVA_EINVAL, "not a sylva.skeleton/1", NULL);
  expect_fail(bad, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "not a QSM", "JSON", NULL);
  write_text(bad,
             "{\"format\":\"sylva.skeleton/1\",\"plants\":[{\"id\":\"t1\",\"stems\":[{\"nodes\":"
             "[[0,-1,0,0,0,0.01,0],[1,0,0,0,1,0.01]]}]}]}");
  expect_fail(bad, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "stem 1, node 2", "[id, parent", NULL);
  write_text(bad,
             "{\"format\":\"sylva.skeleton/1\",\"plants\":[{\"id\":\"t1\",\"stems\":[{\"nodes\":"
             "[[0,-1,0,0,0,0.01,0],[1,0,0,0,1,0.01,0]");
  expect_fail(bad, SYLVA_QSM_SKELETON, 0, SYLVA_EINVAL, "not valid JSON", NULL);
}

/* ---- MAT files written here (libmatio) ---- */

/* How to spoil a model written as a QSM struct. */
typedef struct mat_spoil {
  const char *omit;     /* a cylinder field left out ("cylinder": the whole struct) */
  size_t start_cols;    /* columns of start (3) */
  bool cylinder_double; /* cylinder as a number, not a struct */
} mat_spoil;

static matvar_t *column(const double *v, size_t n, size_t cols) {
  size_t dims[2] = {n, cols};
  return Mat_VarCreate(NULL, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, (void *)v, 0);
}

/* The cylinders of q as TreeQSM's columns (column-major n x 3 for start and axis). */
typedef struct mat_columns {
  double *rad, *len, *sta, *axe, *par, *br, *bo;
} mat_columns;

static mat_columns to_columns(const sylva_qsm *q, size_t start_cols) {
  size_t n = q->count;
  mat_columns c = {malloc(n * sizeof(double)),
                   malloc(n * sizeof(double)),
                   calloc(n * (start_cols ? start_cols : 1), sizeof(double)),
                   malloc(3 * n * sizeof(double)),
                   malloc(n * sizeof(double)),
                   malloc(n * sizeof(double)),
                   malloc(n * sizeof(double))};
  for (size_t i = 0; i < n; i++) {
    c.rad[i] = q->cyl[i].radius;
    c.len[i] = q->cyl[i].length;
    for (size_t k = 0; k < 3; k++) {
      if (k < start_cols) c.sta[k * n + i] = q->cyl[i].start[k];
      c.axe[k * n + i] = q->cyl[i].axis[k];
    }
    c.par[i] = q->cyl[i].parent + 1;
    c.br[i] = q->cyl[i].branch;
    c.bo[i] = q->cyl[i].branch_order;
  }
  return c;
}

static void free_columns(mat_columns *c) {
  free(c->rad), free(c->len), free(c->sta), free(c->axe), free(c->par), free(c->br), free(c->bo);
}

/* Writes models[0..n) as the struct array var (TreeQSM 2.3/2.4) in a file of version ver. */
static bool write_qsm_mat(const char *path, const char *var, const sylva_qsm *models, size_t n,
                          enum mat_ft ver, mat_spoil spoil) {
  mat_t *mat = Mat_CreateVer(path, NULL, ver);
  if (!mat) return false;
  const char *fields[] = {"cylinder", "treedata", NULL};
  const char *no_cylinder[] = {"treedata", NULL};
  bool no_cyl = spoil.omit && strcmp(spoil.omit, "cylinder") == 0;
  size_t dims[2] = {1, n};
  matvar_t *s = Mat_VarCreateStruct2(var, 2, dims, no_cyl ? no_cylinder : fields);
  size_t one[2] = {1, 1};
  for (size_t e = 0; e < n; e++) {
    const sylva_qsm *q = &models[e];
    size_t cols = spoil.start_cols ? spoil.start_cols : 3;
    mat_columns c = to_columns(q, cols);
    const char *all[] = {"radius", "length", "start", "axis", "parent", "branch", "BranchOrder"};
    const char *cf[8];
    int nf = 0;
    for (int k = 0; k < 7; k++)
      if (!spoil.omit || strcmp(spoil.omit, all[k]) != 0) cf[nf++] = all[k];
    cf[nf] = NULL;
    matvar_t *cyl;
    if (spoil.cylinder_double) {
      double one_value = 1;
      cyl = column(&one_value, 1, 1);
    } else {
      cyl = Mat_VarCreateStruct2(NULL, 2, one, cf);
      const double *data[] = {c.rad, c.len, c.sta, c.axe, c.par, c.br, c.bo};
      size_t width[] = {1, 1, cols, 3, 1, 1, 1};
      for (int k = 0; k < 7; k++)
        if (!spoil.omit || strcmp(spoil.omit, all[k]) != 0)
          Mat_VarSetStructFieldByName(cyl, all[k], 0, column(data[k], q->count, width[k]));
    }
    if (!no_cyl)
      Mat_VarSetStructFieldByName(s, "cylinder", e, cyl);
    else
      Mat_VarFree(cyl);
    if (q->has_treedata) {
      const char *tf[] = {"TotalVolume", "TreeHeight", "DBHqsm", NULL};
      matvar_t *t = Mat_VarCreateStruct2(NULL, 2, one, tf);
      Mat_VarSetStructFieldByName(t, "TotalVolume", 0, column(&q->treedata.total_volume, 1, 1));
      Mat_VarSetStructFieldByName(t, "TreeHeight", 0, column(&q->treedata.height, 1, 1));
      Mat_VarSetStructFieldByName(t, "DBHqsm", 0, column(&q->treedata.dbh, 1, 1));
      Mat_VarSetStructFieldByName(s, "treedata", e, t);
    }
    free_columns(&c);
  }
  bool ok = Mat_VarWrite(mat, s, MAT_COMPRESSION_ZLIB) == 0;
  Mat_VarFree(s);
  Mat_Close(mat);
  return ok;
}

/* Writes q as TreeQSM 2.0's variables, leaving out omit. */
static void write_flat_mat(const char *path, const sylva_qsm *q, const char *omit) {
  mat_t *mat = Mat_CreateVer(path, NULL, MAT_FT_MAT5);
  mat_columns c = to_columns(q, 3);
  size_t n = q->count;
  double *boc = malloc(3 * n * sizeof *boc);
  for (size_t i = 0; i < n; i++) boc[i] = c.br[i], boc[n + i] = c.bo[i], boc[2 * n + i] = 1;
  const char *names[] = {"Rad", "Len", "Sta", "Axe", "CPar", "BoC"};
  const double *data[] = {c.rad, c.len, c.sta, c.axe, c.par, boc};
  size_t width[] = {1, 1, 3, 3, 1, 3};
  for (int k = 0; k < 6; k++) {
    if (omit && strcmp(omit, names[k]) == 0) continue;
    size_t dims[2] = {n, width[k]};
    matvar_t *v = Mat_VarCreate(names[k], MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, (void *)data[k], 0);
    CHECK(Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) == 0);
    Mat_VarFree(v);
  }
  Mat_Close(mat);
  free(boc);
  free_columns(&c);
}

/* A small valid model: a stem of three and a branch of two. */
static sylva_qsm small_model(void) {
  sylva_qsm q = {0};
  q.count = 5;
  q.models = 1;
  q.cyl = calloc(q.count, sizeof *q.cyl);
  for (size_t i = 0; i < q.count; i++) {
    sylva_qsm_cylinder *c = &q.cyl[i];
    c->radius = 0.1 - 0.01 * (double)i;
    c->length = 0.5;
    c->axis[2] = 1;
    c->branch = i < 3 ? 1 : 2;
    c->branch_order = i < 3 ? 0 : 1;
  }
  for (int i = 0; i < 3; i++) q.cyl[i].start[2] = 0.5 * i, q.cyl[i].parent = i - 1;
  q.cyl[3] = (sylva_qsm_cylinder){0.04, 0.3, {0, 0, 0.8}, {1, 0, 0}, 1, 2, 1};
  q.cyl[4] = (sylva_qsm_cylinder){0.03, 0.2, {0.3, 0, 0.8}, {0, 0.6, 0.8}, 3, 2, 1};
  q.treedata = (sylva_qsm_treedata){1.5, 0.2, 30, NAN, NAN, NAN};
  q.has_treedata = true;
  return q;
}

static void test_mat_written(void) {
  sylva_qsm q = small_model();
  const char *path = tmp_path("small.mat");
  CHECK(write_qsm_mat(path, "OptQSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0}));
  sylva_qsm r = must_read(path, SYLVA_QSM_UNKNOWN, 0);
  CHECK_INT(differences(&q, &r, true, 0), 0);
  CHECK(r.has_treedata);
  CHECK_NEAR(r.treedata.height, 1.5, 0);
  CHECK(isnan(r.treedata.total_length));
  sylva_qsm_free(&r);
  /* Any struct with a cylinder field will do. */
  CHECK(write_qsm_mat(path, "tree", &q, 1, MAT_FT_MAT5, (mat_spoil){0}));
  r = must_read(path, SYLVA_QSM_MAT, 0);
  CHECK_INT(r.count, 5);
  sylva_qsm_free(&r);
  /* TreeQSM 2.0's variables, without TreeData. */
  write_flat_mat(path, &q, NULL);
  r = must_read(path, SYLVA_QSM_UNKNOWN, 0);
  CHECK_INT(differences(&q, &r, true, 0), 0);
  CHECK(!r.has_treedata);
  sylva_qsm_free(&r);
  /* MATLAB 7.3 (HDF5), when libmatio was built with it (Debian's is). */
  const char *p73 = tmp_path("v73.mat");
  sylva_qsm big = must_read(data_path("qsms_qsm_tree_v240.mat"), SYLVA_QSM_MAT, 0);
  sylva_qsm two[2] = {q, big};
  if (write_qsm_mat(p73, "QSMs", two, 2, MAT_FT_MAT73, (mat_spoil){0})) {
    CHECK_INT(sylva_qsm_sniff(p73), SYLVA_QSM_MAT);
    r = must_read(p73, SYLVA_QSM_UNKNOWN, 2);
    CHECK_INT(r.models, 2);
    CHECK_INT(differences(&big, &r, true, 0), 0);
    CHECK_NEAR(r.treedata.total_volume, big.treedata.total_volume, 0);
    printf("MATLAB 7.3 file of 2 models: model 2 has %zu cylinders\n", r.count);
    sylva_qsm_free(&r);
    expect_fail(p73, SYLVA_QSM_UNKNOWN, 3, SYLVA_ERANGE, "no model 3", "2 models", NULL);
    /* Half of it. */
    size_t len;
    char *bytes = read_bytes(p73, &len);
    const char *half = tmp_path("v73_half.mat");
    write_bytes(half, bytes, len / 2);
    free(bytes);
    expect_fail(half, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "v73_half.mat", "truncated or corrupt",
                NULL);
  } else {
    printf("libmatio writes no MATLAB 7.3 files here: that case is not tested\n");
  }
  sylva_qsm_free(&big);
  sylva_qsm_free(&q);
}

/* ---- Bad input ---- */

static void test_not_a_qsm(void) {
  unsigned char noise[3000];
  uint32_t x = 12345;
  for (size_t i = 0; i < sizeof noise; i++) {
    x = x * 1103515245u + 12345u;
    noise[i] = (unsigned char)(x >> 16);
  }
  const char *bin = tmp_path("noise.bin"), *binmat = tmp_path("noise.mat"),
             *empty = tmp_path("empty.txt"), *emptymat = tmp_path("empty.mat");
  write_bytes(bin, noise, sizeof noise);
  write_bytes(binmat, noise, sizeof noise);
  write_bytes(empty, "", 0);
  write_bytes(emptymat, "", 0);
  CHECK_INT(sylva_qsm_sniff(bin), SYLVA_QSM_UNKNOWN);
  CHECK_INT(sylva_qsm_sniff(empty), SYLVA_QSM_UNKNOWN);
  CHECK_INT(sylva_qsm_sniff(tmp_path("no such file")), SYLVA_QSM_UNKNOWN);
  expect_fail(bin, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "noise.bin", "not a QSM", NULL);
  expect_fail(binmat, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "noise.mat", "not a MATLAB MAT-file",
              NULL);
  expect_fail(bin, SYLVA_QSM_MAT, 0, SYLVA_EINVAL, "not a MATLAB MAT-file", NULL);
  expect_fail(bin, SYLVA_QSM_TEXT, 0, SYLVA_EINVAL, "noise.bin", "row", NULL);
  expect_fail(bin, SYLVA_QSM_CSV, 0, SYLVA_EINVAL, "noise.bin", NULL);
  expect_fail(bin, SYLVA_QSM_SKELETON, 0, SYLVA_EINVAL, "not valid JSON", NULL);
  expect_fail(empty, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "empty file", NULL);
  expect_fail(emptymat, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "empty file", NULL);
  expect_fail(emptymat, SYLVA_QSM_MAT, 0, SYLVA_EINVAL, "not a MATLAB", NULL);
  expect_fail(empty, SYLVA_QSM_TEXT, 0, SYLVA_EINVAL, "no cylinders", NULL);
  expect_fail(empty, SYLVA_QSM_CSV, 0, SYLVA_EINVAL, "no header row", NULL);
  expect_fail(tmp_path("no such file"), SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "No such file", NULL);
  expect_fail(tmpdir, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "directory", NULL);
  /* A MAT-file without a model in it. */
  const char *other = tmp_path("other.mat");
  mat_t *mat = Mat_CreateVer(other, NULL, MAT_FT_MAT5);
  double v = 1;
  size_t dims[2] = {1, 1};
  matvar_t *var = Mat_VarCreate("answer", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &v, 0);
  Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
  Mat_VarFree(var);
  Mat_Close(mat);
  expect_fail(other, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no TreeQSM model", "answer", NULL);
}

static void test_truncated(void) {
  for (size_t f = 0; f < ITSME_FILES; f++) {
    size_t len;
    char *bytes = read_bytes(data_path(itsme[f].name), &len);
    const char *half = tmp_path("half.mat");
    write_bytes(half, bytes, len / 2);
    expect_fail(half, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "half.mat", "truncated or corrupt", NULL);
    /* Cut anywhere else it fails too (and never reads a half-filled model). */
    size_t silent = 0, ok = 0;
    for (size_t cut = 1; cut < len; cut += len / 37 + 1) {
      write_bytes(half, bytes, cut);
      sylva_qsm q;
      char err[512];
      int rc = sylva_qsm_read(half, SYLVA_QSM_UNKNOWN, 0, &q, err, sizeof err);
      if (rc == SYLVA_OK)
        ok++;
      else if (!strstr(err, "truncated or corrupt") && !strstr(err, "not a MATLAB")) {
        silent++;
        printf("  cut at %zu of %zu: %s\n", cut, len, err);
      }
      sylva_qsm_free(&q);
    }
    CHECK_INT(ok, 0);
    CHECK_INT(silent, 0);
    /* A byte changed in the compressed data. */
    bytes[len / 2] ^= 0x55;
    const char *flip = tmp_path("flipped.mat");
    write_bytes(flip, bytes, len);
    /* Not always found: MAT-files carry no checksum, and libmatio does not check
     * zlib's; told here, not checked. */
    sylva_qsm q, orig = must_read(data_path(itsme[f].name), SYLVA_QSM_MAT, 0);
    char err[512];
    int rc = sylva_qsm_read(flip, SYLVA_QSM_UNKNOWN, 0, &q, err, sizeof err);
    if (rc)
      printf("  one byte changed in %s: %s\n", itsme[f].name, err);
    else
      printf("  one byte changed in %s: reads, %zu cylinders differ\n", itsme[f].name,
             differences(&orig, &q, true, 0));
    sylva_qsm_free(&q);
    sylva_qsm_free(&orig);
    free(bytes);
  }
}

static void test_missing(void) {
  sylva_qsm q = small_model();
  const char *path = tmp_path("missing.mat");
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.omit = "radius"});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM.cylinder has no field 'radius'", NULL);
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.omit = "parent"});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no field 'parent'", NULL);
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.omit = "cylinder"});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM has no field 'cylinder'", NULL);
  /* Without branch and order the model still reads: they are 0. */
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.omit = "branch"});
  sylva_qsm r = must_read(path, SYLVA_QSM_MAT, 0);
  CHECK_INT(r.count, 5);
  if (r.count == 5) {
    CHECK_INT(r.cyl[4].branch, 0);
    CHECK_INT(r.cyl[4].branch_order, 1);
  }
  sylva_qsm_free(&r);
  write_flat_mat(path, &q, "Len");
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no variable 'Len'", NULL);
  write_flat_mat(path, &q, "CPar");
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no variable 'CPar'", NULL);
  /* Text: too few columns. */
  const char *txt = tmp_path("missing.txt");
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1", "12 columns", "17", NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n0.1 0.5 0 0 0.5 0 0 1 1 0 1 0 2 0\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2", "14 columns", NULL);
  /* CSV: a column missing, a row short. */
  const char *csv = tmp_path("missing.csv");
  write_text(csv, "ID,parentID,startX,startY,endX,endY,endZ,radius\n0,-1,0,0,0,0,1,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1", "no column 'startZ'", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n"
             "1,0,0,0,1,0,0,2\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 3", "8 fields", "9", NULL);
  sylva_qsm_free(&q);
}

static void test_wrong_shapes(void) {
  sylva_qsm q = small_model();
  const char *path = tmp_path("shape.mat");
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.start_cols = 2});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM.cylinder.start", "shape 5x2", "5x3",
              NULL);
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){.cylinder_double = true});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM.cylinder", "not a 1x1 struct", NULL);
  /* Radius for four cylinders where the others have five. */
  sylva_qsm four = q;
  four.count = 4;
  mat_t *mat = Mat_CreateVer(path, NULL, MAT_FT_MAT5);
  mat_columns c = to_columns(&q, 3);
  const char *names[] = {"Rad", "Len", "Sta", "Axe", "CPar"};
  const double *data[] = {c.rad, c.len, c.sta, c.axe, c.par};
  for (int k = 0; k < 5; k++) {
    size_t dims[2] = {k == 1 ? 4 : 5, k == 2 || k == 3 ? 3 : 1};
    matvar_t *v = Mat_VarCreate(names[k], MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, (void *)data[k], 0);
    Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
    Mat_VarFree(v);
  }
  Mat_Close(mat);
  free_columns(&c);
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "Len has shape 4x1", "expected 5x1", NULL);
  (void)four;
  /* A cylinder field of text. */
  mat = Mat_CreateVer(path, NULL, MAT_FT_MAT5);
  const char *cf[] = {"radius", NULL}, *sf[] = {"cylinder", NULL};
  size_t one[2] = {1, 1}, tdims[2] = {1, 3};
  matvar_t *cyl = Mat_VarCreateStruct2(NULL, 2, one, cf);
  Mat_VarSetStructFieldByName(cyl, "radius", 0,
                              Mat_VarCreate(NULL, MAT_C_CHAR, MAT_T_UINT8, 2, tdims, "abc", 0));
  matvar_t *s = Mat_VarCreateStruct2("QSM", 2, one, sf);
  Mat_VarSetStructFieldByName(s, "cylinder", 0, cyl);
  Mat_VarWrite(mat, s, MAT_COMPRESSION_NONE);
  Mat_VarFree(s);
  Mat_Close(mat);
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM.cylinder.radius is text (1x3)", NULL);
  /* QSM itself not a struct. */
  mat = Mat_CreateVer(path, NULL, MAT_FT_MAT5);
  double d = 1;
  matvar_t *num = Mat_VarCreate("QSM", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, one, &d, 0);
  Mat_VarWrite(mat, num, MAT_COMPRESSION_NONE);
  Mat_VarFree(num);
  Mat_Close(mat);
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL,
              "QSM is a numeric array (1x1), not a TreeQSM struct", NULL);
  sylva_qsm_free(&q);
}

static void test_not_numbers(void) {
  const char *txt = tmp_path("values.txt");
  write_text(txt,
             "radius (m)\tlength (m)\n0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n"
             "0.1 0.5 0 0 abc 0 0 1 1 0 1 0 2 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 3, column 5 (start z)",
              "'abc' is not a number", NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1.5 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1, column 11 (branch)", "whole", NULL);
  const char *csv = tmp_path("values.csv");
  write_text(csv,
             "ID, parentID, startX, startY, startZ, endX, endY, endZ, radius\n"
             "0,-1,0,0,0,0,0,1,0.1\n1,0,0,0,1,0,0,2,0.1\n2,1,0,0,2,0,0,3,0.1\n"
             "3,2,0,0,3,0,0,4,0.1\n4,3,0,0,4,0,0,5,0.1\n5,4,0,0,abc,0,0,6,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 7, column 5 (startZ)",
              "'abc' is not a number", NULL);
  write_text(csv, "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2, column 9 (radius): empty", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n"
             "0,-1,0,0,1,0,0,2,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL,
              "row 3, column 1 (ID): ID 0 is also on row 2", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0.5,-1,0,0,0,0,0,1,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "column 1 (ID)", "whole number", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,\"0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "quoted field never closed", NULL);
}

static void test_not_finite(void) {
  const char *txt = tmp_path("finite.txt");
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\nNaN 0.5 0 0 0.5 0 0 1 1 0 1 0 2 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2: radius nan", "not a finite number",
              NULL);
  write_text(txt, "0.1 Inf 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1: length inf", "not a finite number",
              NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 -inf 1 0 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1: axis y -inf", NULL);
  const char *csv = tmp_path("finite.csv");
  write_text(csv, "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,nan\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2 (ID 0): radius nan", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,inf,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2 (ID 0): length inf", NULL);
  sylva_qsm q = small_model();
  q.cyl[2].axis[0] = NAN;
  const char *path = tmp_path("finite.mat");
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM: cylinder 3: axis x nan", NULL);
  q.cyl[2].axis[0] = 0;
  q.cyl[1].start[1] = INFINITY;
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "cylinder 2: start y inf", NULL);
  sylva_qsm_free(&q);
  /* A parent of NaN in a .mat. */
  q = small_model();
  const char *flat = tmp_path("finite_flat.mat");
  mat_t *mat = Mat_CreateVer(flat, NULL, MAT_FT_MAT5);
  mat_columns c = to_columns(&q, 3);
  c.par[3] = NAN;
  const char *names[] = {"Rad", "Len", "Sta", "Axe", "CPar"};
  const double *data[] = {c.rad, c.len, c.sta, c.axe, c.par};
  for (int k = 0; k < 5; k++) {
    size_t dims[2] = {5, k == 2 || k == 3 ? 3 : 1};
    matvar_t *v = Mat_VarCreate(names[k], MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, (void *)data[k], 0);
    Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
    Mat_VarFree(v);
  }
  Mat_Close(mat);
  free_columns(&c);
  expect_fail(flat, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "CPar(4) = nan", "not a cylinder", NULL);
  sylva_qsm_free(&q);
}

static void test_not_positive(void) {
  const char *txt = tmp_path("positive.txt");
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n0 0.5 0 0 0.5 0 0 1 1 0 1 0 2 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2: radius 0 is not above 0", NULL);
  write_text(txt, "0.1 -0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1: length -0.5 is not above 0", NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 0 0 0 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1: axis (0, 0, 0)", NULL);
  const char *csv = tmp_path("positive.csv");
  write_text(csv, "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n7,-1,1,2,3,1,2,3,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2 (ID 7): length 0 is not above 0",
              NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n7,-1,1,2,3,1,2,4,-0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "radius -0.1 is not above 0", NULL);
  sylva_qsm q = small_model();
  q.cyl[4].length = -1;
  const char *path = tmp_path("positive.mat");
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "cylinder 5: length -1 is not above 0",
              NULL);
  q.cyl[4].length = 0.2;
  q.cyl[0].radius = 0;
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "cylinder 1: radius 0 is not above 0",
              NULL);
  sylva_qsm_free(&q);
}

static void test_parents(void) {
  const char *txt = tmp_path("parents.txt");
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n0.1 0.5 0 0 0.5 0 0 1 99 0 1 0 2 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2, column 9 (parent)",
              "99 is not a cylinder (1..2", NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 -1 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "-1 is not a cylinder", NULL);
  /* Cylinders 2 and 3 each other's parent; then one its own. */
  write_text(txt,
             "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n0.1 0.5 0 0 0.5 0 0 1 3 0 1 0 2 0 0.1\n"
             "0.1 0.5 0 0 1 0 0 1 2 0 1 0 2 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 2: its parents form a cycle",
              "row 2 -> row 3 -> row 2", NULL);
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 1 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 1: its parents form a cycle", NULL);
  const char *csv = tmp_path("parents.csv");
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n"
             "1,99,0,0,1,0,0,2,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "row 3, column 2 (parentID)",
              "no row has ID 99", NULL);
  write_text(csv,
             "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n"
             "5,6,0,0,1,0,0,2,0.1\n6,5,0,0,2,0,0,3,0.1\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "cycle", "row 3 (ID 5) -> row 4 (ID 6)",
              NULL);
  sylva_qsm q = small_model();
  const char *path = tmp_path("parents.mat");
  q.cyl[2].parent = 499;
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM.cylinder.parent(3) = 500",
              "not a cylinder (1..5, or 0 for a root)", NULL);
  q.cyl[2].parent = 4;
  q.cyl[3].parent = 2;
  write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0});
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSM: cylinder 3: its parents form a cycle",
              "cylinder 3 -> cylinder 5 -> cylinder 4 -> cylinder 3", NULL);
  sylva_qsm_free(&q);
}

static void test_empty(void) {
  const char *txt = tmp_path("empty_model.txt");
  write_text(txt, "radius (m)\tlength (m)\tstart_point\taxis_direction\tparent\textension\n\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no cylinders below the header row", NULL);
  const char *csv = tmp_path("empty_model.csv");
  write_text(csv, " ID, parentID, startX, startY, startZ, endX, endY, endZ, radius\n");
  expect_fail(csv, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "no cylinders", NULL);
  sylva_qsm q = {0};
  const char *path = tmp_path("empty_model.mat");
  CHECK(write_qsm_mat(path, "QSM", &q, 1, MAT_FT_MAT5, (mat_spoil){0}));
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL,
              "QSM.cylinder.radius is empty: no cylinders", NULL);
  CHECK(write_qsm_mat(path, "QSMs", &q, 0, MAT_FT_MAT5, (mat_spoil){0}));
  expect_fail(path, SYLVA_QSM_UNKNOWN, 0, SYLVA_EINVAL, "QSMs is an empty struct array", NULL);
}

static void test_model_range(void) {
  const char *path = data_path("qsms_qsms_tree_v240_notria.mat");
  expect_fail(path, SYLVA_QSM_UNKNOWN, 11, SYLVA_ERANGE, "no model 11", "QSMs holds 10 models",
              NULL);
  expect_fail(path, SYLVA_QSM_UNKNOWN, -1, SYLVA_EINVAL, "model -1", NULL);
  expect_fail(data_path("qsms_qsm_tree_v240.mat"), SYLVA_QSM_UNKNOWN, 2, SYLVA_ERANGE,
              "no model 2: QSM holds 1 model", NULL);
  expect_fail(data_path("qsms_qsm_tree_v200.mat"), SYLVA_QSM_UNKNOWN, 2, SYLVA_ERANGE,
              "no model 2: the file holds 1 model (TreeQSM 2.0", NULL);
  /* Two models, the second spoilt: the first reads, the second is named. */
  sylva_qsm two[2] = {small_model(), small_model()};
  two[1].cyl[0].radius = 0;
  two[1].cyl[3].parent = 99;
  const char *mat = tmp_path("two.mat");
  CHECK(write_qsm_mat(mat, "QSMs", two, 2, MAT_FT_MAT5, (mat_spoil){0}));
  sylva_qsm first = must_read(mat, SYLVA_QSM_UNKNOWN, 0);
  CHECK_INT(first.models, 2);
  CHECK_INT(differences(&first, &two[0], true, 0), 0);
  sylva_qsm_free(&first);
  expect_fail(mat, SYLVA_QSM_UNKNOWN, 2, SYLVA_EINVAL, "QSMs(2).cylinder.parent(4) = 100", NULL);
  two[1].cyl[3].parent = 1;
  CHECK(write_qsm_mat(mat, "QSMs", two, 2, MAT_FT_MAT5, (mat_spoil){0}));
  expect_fail(mat, SYLVA_QSM_UNKNOWN, 2, SYLVA_EINVAL, "QSMs(2): cylinder 1: radius 0", NULL);
  expect_fail(mat, SYLVA_QSM_UNKNOWN, 3, SYLVA_ERANGE, "no model 3: QSMs holds 2 models", NULL);
  sylva_qsm_free(&two[0]);
  sylva_qsm_free(&two[1]);
  const char *txt = tmp_path("range.txt");
  write_text(txt, "0.1 0.5 0 0 0 0 0 1 0 2 1 0 1 0 0.1\n");
  expect_fail(txt, SYLVA_QSM_UNKNOWN, 2, SYLVA_ERANGE, "no model 2", NULL);
  sylva_qsm q = must_read(txt, SYLVA_QSM_UNKNOWN, 1);
  CHECK_INT(q.models, 1);
  sylva_qsm_free(&q);
}

/* ---- The check, names and sniffing ---- */

static void expect_check(const sylva_qsm *q, const char *want) {
  char err[512] = "";
  int rc = sylva_qsm_check(q, err, sizeof err);
  printf("  check: %s\n", err);
  CHECK_INT(rc, SYLVA_EINVAL);
  if (!strstr(err, want)) {
    check_failed++;
    fprintf(stderr, "message '%s' lacks '%s'\n", err, want);
  }
}

static void test_check(void) {
  sylva_qsm q = small_model();
  char err[256];
  CHECK_INT(sylva_qsm_check(&q, err, sizeof err), SYLVA_OK);
  q.cyl[1].radius = 0;
  expect_check(&q, "cylinder 2: radius 0 is not above 0");
  q.cyl[1].radius = 0.1;
  q.cyl[1].length = -2;
  expect_check(&q, "cylinder 2: length -2 is not above 0");
  q.cyl[1].length = 0.5;
  q.cyl[4].axis[0] = q.cyl[4].axis[1] = q.cyl[4].axis[2] = 0;
  expect_check(&q, "cylinder 5: axis (0, 0, 0)");
  q.cyl[4].axis[2] = 1;
  q.cyl[3].parent = 5;
  expect_check(&q, "cylinder 4: parent 6 is not a cylinder (1..5, or 0 for a root)");
  q.cyl[3].parent = -2;
  expect_check(&q, "cylinder 4: parent -1 is not a cylinder");
  q.cyl[3].parent = 1;
  q.cyl[0].parent = 4;
  expect_check(&q,
               "its parents form a cycle (cylinder 1 -> cylinder 5 -> cylinder 4 -> cylinder 2 -> "
               "cylinder 1)");
  q.cyl[0].parent = -1;
  CHECK_INT(sylva_qsm_check(&q, NULL, 0), SYLVA_OK);
  /* A long cycle is told in part. */
  sylva_qsm ring = {0};
  ring.count = 20;
  ring.cyl = calloc(ring.count, sizeof *ring.cyl);
  for (size_t i = 0; i < ring.count; i++) {
    ring.cyl[i] = (sylva_qsm_cylinder){0.1, 1, {0, 0, 0}, {0, 0, 1}, (int)((i + 1) % 20), 0, 0};
  }
  expect_check(&ring, "... -> cylinder 1)");
  /* A model the writers refuse. */
  CHECK_INT(sylva_qsm_write_text(&ring, tmp_path("ring.txt")), SYLVA_EINVAL);
  CHECK_INT(sylva_qsm_write_csv(&ring, tmp_path("ring.csv")), SYLVA_EINVAL);
  sylva_qsm_free(&ring);
  sylva_qsm empty = {0};
  expect_check(&empty, "no cylinders");
  sylva_qsm_free(&q);
  sylva_qsm_free(&q); /* twice is harmless */
}

static void test_formats(void) {
  const char *names[] = {"mat", "text", "csv", "skeleton"};
  for (int f = SYLVA_QSM_MAT; f <= SYLVA_QSM_SKELETON; f++) {
    CHECK_INT(sylva_qsm_format_named(names[f - 1]), f);
    CHECK(strcmp(sylva_qsm_format_name((sylva_qsm_format)f), names[f - 1]) == 0);
  }
  CHECK_INT(sylva_qsm_format_named("json"), SYLVA_QSM_UNKNOWN);
  CHECK_INT(sylva_qsm_format_named(NULL), SYLVA_QSM_UNKNOWN);
  CHECK(strcmp(sylva_qsm_format_name(SYLVA_QSM_UNKNOWN), "unknown") == 0);
  CHECK(strcmp(sylva_qsm_format_name((sylva_qsm_format)42), "unknown") == 0);
  /* Sniffing by the first bytes, then the extension. */
  const char *p = tmp_path("sniff.dat");
  write_text(p, "\xEF\xBB\xBF ID , \"parentID\",startX\n");
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_CSV);
  write_text(p, "0.1\t0.5\n");
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_TEXT);
  write_text(p, "\n  {\"format\": \"sylva.skeleton/1\"}");
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_SKELETON);
  write_text(p, "{\"format\": \"sylva.scenario/1\"}");
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_UNKNOWN);
  write_text(p, "MATLAB 5.0 MAT-file, Platform: GLNXA64");
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_MAT);
  write_bytes(p, "\x89HDF\r\n\x1a\n\0\0", 10);
  CHECK_INT(sylva_qsm_sniff(p), SYLVA_QSM_MAT);
  write_text(tmp_path("sniff.CSV"), "a,b\n");
  CHECK_INT(sylva_qsm_sniff(tmp_path("sniff.CSV")), SYLVA_QSM_CSV);
  write_text(tmp_path("sniff.json"), "\n");
  CHECK_INT(sylva_qsm_sniff(tmp_path("sniff.json")), SYLVA_QSM_UNKNOWN);
  CHECK_INT(sylva_qsm_sniff(tmpdir), SYLVA_QSM_UNKNOWN);
}

/* Removes the temporary directory and what the tests wrote in it. */
static void remove_tmpdir(void) {
  DIR *d = opendir(tmpdir);
  if (!d) return;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) remove(tmp_path(e->d_name));
  closedir(d);
  rmdir(tmpdir);
}

int main(int argc, char **argv) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/sylva-import-XXXXXX");
  if (!mkdtemp(tmpdir)) {
    perror("mkdtemp");
    return 1;
  }
  static const check_test tests[] = {
      CHECK_TEST(itsme),        CHECK_TEST(round_trip),       CHECK_TEST(text_columns),
      CHECK_TEST(treeqsm_text), CHECK_TEST(simpleforest_csv), CHECK_TEST(skeleton),
      CHECK_TEST(mat_written),  CHECK_TEST(not_a_qsm),        CHECK_TEST(truncated),
      CHECK_TEST(missing),      CHECK_TEST(wrong_shapes),     CHECK_TEST(not_numbers),
      CHECK_TEST(not_finite),   CHECK_TEST(not_positive),     CHECK_TEST(parents),
      CHECK_TEST(empty),        CHECK_TEST(model_range),      CHECK_TEST(check),
      CHECK_TEST(formats),
  };
  CHECK_RUN(argc, argv, 1, tests);
  remove_tmpdir();
  return check_summary("import");
}
