/* The stand's figures (docs/model.md, "Stands"): stems per hectare, basal area,
 * quadratic mean diameter, dominant height, Reineke's SDI and the spreads, over the
 * stems alive, per hectare of the ground the plants occupy. */
#include <math.h>
#include <stdlib.h>

#include "world_impl.h"

/* Reineke's (1933) exponent of the self-thinning line, and the SDI's reference
 * diameter, cm. */
#define REINEKE_SLOPE 1.605
#define SDI_REFERENCE_CM 25.0
/* Dominant height: the mean height of the thickest stems, this many a hectare. */
#define DOMINANT_PER_HA 100.0

typedef struct point2 {
  double x, y;
} point2;

static int cmp_point(const void *a, const void *b) {
  const point2 *p = a, *q = b;
  if (p->x != q->x) return p->x < q->x ? -1 : 1;
  return (p->y > q->y) - (p->y < q->y);
}

static double cross(point2 o, point2 a, point2 b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* The convex hull's area and perimeter of n points sorted by cmp_point (Andrew's
 * monotone chain); hull has room for 2 n points. */
static void hull_measure(const point2 *p, size_t n, point2 *hull, double *area, double *perimeter) {
  size_t k = 0;
  for (size_t i = 0; i < n; i++) { /* lower hull */
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) k--;
    hull[k++] = p[i];
  }
  for (size_t i = n - 1, t = k + 1; i-- > 0;) { /* upper hull */
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) k--;
    hull[k++] = p[i];
  }
  if (k > 1) k--; /* the last point repeats the first */
  double a = 0.0, len = 0.0;
  for (size_t i = 0; i < k; i++) {
    point2 u = hull[i], v = hull[(i + 1) % k];
    a += u.x * v.y - v.x * u.y;
    len += hypot(v.x - u.x, v.y - u.y);
  }
  *area = 0.5 * fabs(a);
  *perimeter = k > 1 ? len : 0.0;
}

/* The mean distance from each of n points (sorted by x) to its nearest other point. */
static double mean_spacing(const point2 *p, size_t n) {
  double sum = 0.0;
  for (size_t i = 0; i < n; i++) {
    double best = INFINITY;
    for (size_t j = i + 1; j < n && p[j].x - p[i].x < best; j++) {
      double d = hypot(p[j].x - p[i].x, p[j].y - p[i].y);
      if (d < best) best = d;
    }
    for (size_t j = i; j-- > 0 && p[i].x - p[j].x < best;) {
      double d = hypot(p[j].x - p[i].x, p[j].y - p[i].y);
      if (d < best) best = d;
    }
    sum += best;
  }
  return sum / (double)n;
}

/* The ground the stems occupy, m^2: the convex hull of their roots widened by half
 * their mean spacing r (the hull's area, its perimeter times r and pi r^2: a disc of
 * radius r swept around it); NaN for fewer than two distinct roots. Roots of dead and
 * fallen stems count: the ground stays the stand's. */
static double occupied_area(const sylva_world *w) {
  size_t n = (size_t)w->stem_count;
  if (n < 2) return NAN;
  point2 *p = sylva__malloc(3 * n * sizeof *p);
  if (!p) return NAN; /* the figures per hectare are then null, nothing else */
  for (size_t k = 0; k < n; k++) p[k] = (point2){w->stems[k].root[0], w->stems[k].root[1]};
  qsort(p, n, sizeof *p, cmp_point);
  size_t m = 1; /* distinct points */
  for (size_t k = 1; k < n; k++)
    if (p[k].x != p[m - 1].x || p[k].y != p[m - 1].y) p[m++] = p[k];
  double area = NAN;
  if (m >= 2) {
    double hull, perimeter, r = 0.5 * mean_spacing(p, m);
    hull_measure(p, m, p + m, &hull, &perimeter);
    area = hull + perimeter * r + 3.14159265358979323846 * r * r;
  }
  sylva__free(p);
  return area;
}

typedef struct ranked_stem {
  double dbh, height;
  int stem;
} ranked_stem;

/* Thickest first; a stem without a dbh after every stem with one; then stem order. */
static int cmp_thickest(const void *a, const void *b) {
  const ranked_stem *p = a, *q = b;
  bool pn = isnan(p->dbh), qn = isnan(q->dbh);
  if (pn != qn) return pn ? 1 : -1;
  if (!pn && p->dbh != q->dbh) return p->dbh > q->dbh ? -1 : 1;
  return (p->stem > q->stem) - (p->stem < q->stem);
}

/* Population coefficient of variation of n values (NaN for none). */
static double cv_of(const double *v, size_t n) {
  if (!n) return NAN;
  double mean = 0.0, ss = 0.0;
  for (size_t i = 0; i < n; i++) mean += v[i];
  mean /= (double)n;
  for (size_t i = 0; i < n; i++) ss += (v[i] - mean) * (v[i] - mean);
  return mean > 0.0 ? sqrt(ss / (double)n) / mean : NAN;
}

/* The figures of w's alive stems over `area` m^2 into *o. */
static void stand_figures(const sylva_world *w, double area, sylva_stand_stats *o) {
  *o = (sylva_stand_stats){.area = area};
  double ha = o->area / 10000.0;
  size_t n = 0, nd = 0;
  ranked_stem *r = sylva__malloc(((size_t)w->stem_count + 1) * sizeof *r);
  double *v = sylva__malloc(((size_t)w->stem_count + 1) * sizeof *v);
  double basal = 0.0, d2 = 0.0;
  for (int k = 0; k < w->stem_count; k++) {
    const sylva_stem_stats *s = &w->stems[k].stats;
    if (s->died == w->iteration) o->died++;
    if (!s->alive) continue;
    o->alive++;
    if (r) r[n++] = (ranked_stem){s->dbh, s->height, k};
    if (isnan(s->dbh)) continue;
    nd++;
    basal += 3.14159265358979323846 * 0.25 * s->dbh * s->dbh;
    d2 += s->dbh * s->dbh;
  }
  o->stems_per_ha = o->alive / ha;
  o->basal_area = basal / ha;
  o->qmd = nd ? 100.0 * sqrt(d2 / (double)nd) : NAN;
  o->sdi = o->stems_per_ha * pow(o->qmd / SDI_REFERENCE_CM, REINEKE_SLOPE);
  o->dominant_height = o->cv_height = o->cv_dbh = NAN;
  if (r && v && n) {
    qsort(r, n, sizeof *r, cmp_thickest);
    size_t dom = n;
    if (isfinite(ha)) {
      double want = floor(DOMINANT_PER_HA * ha + 0.5);
      if (want < 1.0) want = 1.0;
      if (want < (double)n) dom = (size_t)want;
    }
    double h = 0.0;
    for (size_t i = 0; i < dom; i++) h += r[i].height;
    o->dominant_height = h / (double)dom;
    /* the spreads in stem order, as the stems are listed */
    size_t m = 0;
    for (int k = 0; k < w->stem_count; k++)
      if (w->stems[k].stats.alive) v[m++] = w->stems[k].stats.height;
    o->cv_height = cv_of(v, m);
    m = 0;
    for (int k = 0; k < w->stem_count; k++)
      if (w->stems[k].stats.alive && !isnan(w->stems[k].stats.dbh)) v[m++] = w->stems[k].stats.dbh;
    o->cv_dbh = cv_of(v, m);
  }
  sylva__free(r);
  sylva__free(v);
}

/* The stand's area: the def's, or the roots' widened hull. */
static double stand_area_of(const sylva_world *w) {
  return w->def.stand_area > 0.0 ? w->def.stand_area : occupied_area(w);
}

void sylva__stand(sylva_world *w) {
  if (w->stand_stems != w->stem_count) { /* roots never move: only a planting changes it */
    w->stand_area = stand_area_of(w);
    w->stand_stems = w->stem_count;
  }
  stand_figures(w, w->stand_area, &w->stand);
  w->stand_fresh = true;
}

void sylva__stand_stale(sylva_world *w) { w->stand_fresh = false; }

void sylva_world_stand(const sylva_world *w, sylva_stand_stats *out) {
  if (w->stand_fresh) {
    *out = w->stand;
    return;
  }
  /* after plantings (which only mark the figures stale, so that planting n trees is
   * not n passes over the stand): found now, as the next step will find them */
  double area = w->stand_stems == w->stem_count ? w->stand_area : stand_area_of(w);
  stand_figures(w, area, out);
}
