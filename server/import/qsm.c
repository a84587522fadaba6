#include "qsm.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sylva/status.h"

/* ---- The model ---- */

void sylva_qsm_free(sylva_qsm *q) {
  if (!q) return;
  free(q->cyl);
  memset(q, 0, sizeof *q);
}


int sylva__qsm_grow(sylva_qsm *q, size_t *cap) {
  if (q->count < *cap) return SYLVA_OK;
  size_t n = *cap ? *cap * 2 : 256;
  if (n > SIZE_MAX / sizeof *q->cyl || n > (size_t)INT_MAX) return SYLVA_ENOMEM;
  sylva_qsm_cylinder *c = realloc(q->cyl, n * sizeof *c);
  if (!c) return SYLVA_ENOMEM;
  q->cyl = c;
  *cap = n;
  return SYLVA_OK;
}

/* ---- Formats ---- */

static const char *const format_names[] = {
    [SYLVA_QSM_UNKNOWN] = "unknown", [SYLVA_QSM_MAT] = "mat",           [SYLVA_QSM_TEXT] = "text",
    [SYLVA_QSM_CSV] = "csv",         [SYLVA_QSM_SKELETON] = "skeleton",
};

sylva_qsm_format sylva_qsm_format_named(const char *s) {
  if (!s) return SYLVA_QSM_UNKNOWN;
  for (int f = SYLVA_QSM_MAT; f <= SYLVA_QSM_SKELETON; f++)
    if (strcmp(s, format_names[f]) == 0) return (sylva_qsm_format)f;
  return SYLVA_QSM_UNKNOWN;
}

const char *sylva_qsm_format_name(sylva_qsm_format f) {
  if ((int)f < SYLVA_QSM_UNKNOWN || f > SYLVA_QSM_SKELETON) return format_names[0];
  return format_names[f];
}

/* What the first bytes of a file say, with the reason when they say nothing. */
typedef enum sniff_kind {
  SNIFF_EMPTY,
  SNIFF_BINARY,
  SNIFF_JSON_OTHER, /* JSON, but not sylva.skeleton/1 */
  SNIFF_FORMAT,     /* a format */
} sniff_kind;

static bool has_extension(const char *path, const char *ext) {
  const char *slash = strrchr(path, '/');
  const char *dot = strrchr(slash ? slash : path, '.');
  if (!dot) return false;
  for (size_t i = 0;; i++) {
    char a = dot[i], b = ext[i];
    if (a >= 'A' && a <= 'Z') a = (char)(a - 'A' + 'a');
    if (a != b) return false;
    if (!a) return true;
  }
}

static bool contains(const char *buf, size_t n, const char *needle) {
  size_t k = strlen(needle);
  for (size_t i = 0; i + k <= n; i++)
    if (memcmp(buf + i, needle, k) == 0) return true;
  return false;
}

/* A first line whose comma-separated names include ID and parentID (blanks and
 * quotes around a name allowed). */
static bool csv_header(const char *buf, size_t n) {
  bool id = false, parent = false;
  size_t i = 0;
  while (i < n && buf[i] != '\n' && buf[i] != '\r') {
    size_t a = i;
    while (i < n && buf[i] != ',' && buf[i] != '\n' && buf[i] != '\r') i++;
    size_t b = i;
    while (a < b && (buf[a] == ' ' || buf[a] == '\t' || buf[a] == '"')) a++;
    while (b > a && (buf[b - 1] == ' ' || buf[b - 1] == '\t' || buf[b - 1] == '"')) b--;
    if (b - a == 2 && memcmp(buf + a, "ID", 2) == 0) id = true;
    if (b - a == 8 && memcmp(buf + a, "parentID", 8) == 0) parent = true;
    if (i < n && buf[i] == ',') i++;
  }
  return id && parent;
}

static sniff_kind sniff_bytes(const char *path, const char *buf, size_t n, sylva_qsm_format *f) {
  *f = SYLVA_QSM_UNKNOWN;
  if (n == 0) return SNIFF_EMPTY;
  /* MATLAB 5 and 7.3 files open with a text header: "MATLAB 5.0 MAT-file, ...". A
   * bare HDF5 file (an HDF5 signature at 0, or at 512 after a user block) is read
   * by libmatio too. */
  if ((n >= 7 && memcmp(buf, "MATLAB ", 7) == 0 && contains(buf, n < 116 ? n : 116, "MAT-file")) ||
      (n >= 8 && memcmp(buf, "\x89HDF\r\n\x1a\n", 8) == 0) ||
      (n >= 520 && memcmp(buf + 512, "\x89HDF\r\n\x1a\n", 8) == 0)) {
    *f = SYLVA_QSM_MAT;
    return SNIFF_FORMAT;
  }
  for (size_t i = 0; i < n; i++) {
    unsigned char ch = (unsigned char)buf[i];
    if (ch < 0x20 && ch != '\t' && ch != '\n' && ch != '\r' && ch != '\f' && ch != '\v') {
      /* Binary without a MATLAB header: named .mat, libmatio tells what it is. */
      if (has_extension(path, ".mat")) {
        *f = SYLVA_QSM_MAT;
        return SNIFF_FORMAT;
      }
      return SNIFF_BINARY;
    }
  }
  size_t i = 0;
  if (n >= 3 && memcmp(buf, "\xEF\xBB\xBF", 3) == 0) i = 3;
  while (i < n && (buf[i] == ' ' || buf[i] == '\t' || buf[i] == '\n' || buf[i] == '\r')) i++;
  if (i == n) return SNIFF_EMPTY;
  if (buf[i] == '{' || buf[i] == '[') {
    if (contains(buf + i, n - i, "sylva.skeleton/1")) {
      *f = SYLVA_QSM_SKELETON;
      return SNIFF_FORMAT;
    }
    return SNIFF_JSON_OTHER;
  }
  if (csv_header(buf + i, n - i))
    *f = SYLVA_QSM_CSV;
  else if (has_extension(path, ".mat"))
    *f = SYLVA_QSM_MAT; /* cut inside its header, say */
  else if (has_extension(path, ".csv"))
    *f = SYLVA_QSM_CSV; /* its reader names what is missing */
  else if (has_extension(path, ".json"))
    *f = SYLVA_QSM_SKELETON;
  else
    *f = SYLVA_QSM_TEXT;
  return SNIFF_FORMAT;
}

enum { SNIFF_BYTES = 4096 };

/* Reads the first bytes of path; 0 or an errno value. */
static int sniff_read(const char *path, char *buf, size_t *n) {
  *n = 0;
  FILE *fp = fopen(path, "rb");
  if (!fp) return errno;
  struct stat st;
  if (fstat(fileno(fp), &st) == 0 && S_ISDIR(st.st_mode)) {
    fclose(fp);
    return EISDIR;
  }
  *n = fread(buf, 1, SNIFF_BYTES, fp);
  int e = ferror(fp) ? (errno ? errno : EIO) : 0;
  fclose(fp);
  return e;
}

sylva_qsm_format sylva_qsm_sniff(const char *path) {
  char buf[SNIFF_BYTES];
  size_t n;
  if (!path || sniff_read(path, buf, &n) != 0) return SYLVA_QSM_UNKNOWN;
  sylva_qsm_format f;
  sniff_bytes(path, buf, n, &f);
  return f;
}

/* ---- Checking ---- */

static void name_cylinder(const void *ctx, size_t i, char *buf, size_t len) {
  (void)ctx;
  snprintf(buf, len, "cylinder %zu", i + 1);
}

/* "not finite" or "not above 0" for a value that must be both. */
static const char *positive_problem(double v) {
  if (!isfinite(v)) return "is not a finite number";
  if (!(v > 0)) return "is not above 0";
  return NULL;
}

int sylva__qsm_check_named(const sylva_qsm *q, sylva__qsm_namer name, const void *ctx, char *err,
                           size_t errlen) {
  if (!name) name = name_cylinder;
  if (!q || q->count == 0) return server_fail(err, errlen, SYLVA_EINVAL, "no cylinders");
  if (q->count > (size_t)INT_MAX)
    return server_fail(err, errlen, SYLVA_ETOOBIG, "%zu cylinders: more than %d", q->count,
                           INT_MAX);
  char who[96];
  for (size_t i = 0; i < q->count; i++) {
    const sylva_qsm_cylinder *c = &q->cyl[i];
    const char *why;
    if ((why = positive_problem(c->radius))) {
      name(ctx, i, who, sizeof who);
      return server_fail(err, errlen, SYLVA_EINVAL, "%s: radius %g %s", who, c->radius, why);
    }
    if ((why = positive_problem(c->length))) {
      name(ctx, i, who, sizeof who);
      return server_fail(err, errlen, SYLVA_EINVAL, "%s: length %g %s", who, c->length, why);
    }
    for (int k = 0; k < 3; k++) {
      if (!isfinite(c->start[k])) {
        name(ctx, i, who, sizeof who);
        return server_fail(err, errlen, SYLVA_EINVAL, "%s: start %c %g is not a finite number",
                               who, "xyz"[k], c -> start[k]);
      }
      if (!isfinite(c->axis[k])) {
        name(ctx, i, who, sizeof who);
        return server_fail(err, errlen, SYLVA_EINVAL, "%s: axis %c %g is not a finite number",
                               who, "xyz"[k], c -> axis[k]);
      }
    }
    if (c->axis[0] == 0 && c->axis[1] == 0 && c->axis[2] == 0) {
      name(ctx, i, who, sizeof who);
      return server_fail(err, errlen, SYLVA_EINVAL, "%s: axis (0, 0, 0) has no direction", who);
    }
    if (c->parent < -1 || c->parent >= (int)q->count) {
      name(ctx, i, who, sizeof who);
      /* Told as TreeQSM counts: cylinders from 1, 0 for none. */
      return server_fail(err, errlen, SYLVA_EINVAL,
                             "%s: parent %lld is not a cylinder (1..%zu, or 0 for a root)", who,
                             (long long)c->parent + 1, q->count);
    }
  }
  /* Cycles: follow each chain of parents until a root or a cylinder already known
   * to reach one; meeting the chain itself again is a cycle. */
  unsigned char *state = calloc(q->count, 1); /* 0 unseen, 1 on the chain, 2 reaches a root */
  if (!state) return server_fail(err, errlen, SYLVA_ENOMEM, "out of memory");
  int rc = SYLVA_OK;
  for (size_t i = 0; i < q->count && !rc; i++) {
    size_t j = i;
    while (state[j] == 0) {
      state[j] = 1;
      if (q->cyl[j].parent < 0) break;
      j = (size_t)q->cyl[j].parent;
    }
    if (state[j] == 1 && q->cyl[j].parent >= 0) {
      /* j is on the cycle: name its members, a few at most. */
      char msg[512];
      size_t len = 0;
      size_t k = j, shown = 0;
      do {
        name(ctx, k, who, sizeof who);
        int w = snprintf(msg + len, sizeof msg - len, "%s%s", shown ? " -> " : "", who);
        if (w > 0 && (size_t)w < sizeof msg - len) len += (size_t)w;
        k = (size_t)q->cyl[k].parent;
        shown++;
      } while (k != j && shown < 8);
      name(ctx, j, who, sizeof who);
      rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: its parents form a cycle (%s -> %s%s)",
                           who, msg, k == j ? "" : "... -> ", who);
    }
    for (j = i; state[j] == 1; j = (size_t)q->cyl[j].parent) {
      state[j] = 2;
      if (q->cyl[j].parent < 0) break;
    }
  }
  free(state);
  return rc;
}

int sylva_qsm_check(const sylva_qsm *q, char *err, size_t errlen) {
  return sylva__qsm_check_named(q, NULL, NULL, err, errlen);
}

void sylva__qsm_normalise(sylva_qsm *q) {
  for (size_t i = 0; i < q->count; i++) {
    double *a = q->cyl[i].axis;
    double n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if (fabs(n2 - 1) <= 1e-12) continue;
    /* Scaled by the largest component first, so that neither a tiny nor a huge
     * vector under- or overflows on the way. */
    double m = fmax(fabs(a[0]), fmax(fabs(a[1]), fabs(a[2])));
    double x = a[0] / m, y = a[1] / m, z = a[2] / m;
    double n = sqrt(x * x + y * y + z * z);
    a[0] = x / n;
    a[1] = y / n;
    a[2] = z / n;
  }
}

/* ---- sylva.skeleton/1 ---- */

/* The skeleton file: its plant, and each cylinder's node id for messages. */
typedef struct skel_names {
  const char *plant;
  const double *node_id; /* per cylinder */
} skel_names;

static void skel_name(const void *ctx, size_t i, char *buf, size_t len) {
  const skel_names *s = ctx;
  snprintf(buf, len, "plant '%s', node %.0f", s->plant, s->node_id[i]);
}

/* A node: [id, parent, x, y, z, radius, birth]. */
typedef struct skel_node {
  double id, parent, pos[3], radius;
  int cyl; /* its cylinder; -1 for a root node */
} skel_node;

static int skel_cmp_id(const void *a, const void *b) {
  const skel_node *x = *(skel_node *const *)a, *y = *(skel_node *const *)b;
  return (x->id > y->id) - (x->id < y->id);
}

static skel_node *skel_find(skel_node **by_id, size_t n, double id) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (by_id[mid]->id < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && by_id[lo]->id == id ? by_id[lo] : NULL;
}

static bool whole(double v) { return isfinite(v) && v == floor(v) && fabs(v) < 9007199254740992.0; }

/* Reads the whole file into a NUL-terminated buffer; 0 or an errno value. */
static int read_all(const char *path, char **data, size_t *len) {
  *data = NULL;
  *len = 0;
  FILE *fp = fopen(path, "rb");
  if (!fp) return errno;
  size_t cap = 1 << 16, n = 0;
  char *buf = malloc(cap + 1);
  int rc = buf ? 0 : ENOMEM;
  while (!rc) {
    if (n == cap) {
      if (cap > (SIZE_MAX - 1) / 2) {
        rc = EFBIG;
        break;
      }
      char *g = realloc(buf, cap * 2 + 1);
      if (!g) {
        rc = ENOMEM;
        break;
      }
      buf = g;
      cap *= 2;
    }
    size_t got = fread(buf + n, 1, cap - n, fp);
    n += got;
    if (got == 0) {
      if (ferror(fp)) rc = errno ? errno : EIO;
      break;
    }
  }
  fclose(fp);
  if (rc) {
    free(buf);
    return rc;
  }
  buf[n] = '\0';
  *data = buf;
  *len = n;
  return 0;
}

static int read_skeleton(const char *path, int model, sylva_qsm *q, char *err, size_t errlen) {
  char *text;
  size_t len;
  int e = read_all(path, &text, &len);
  if (e)
    return server_fail(err, errlen, e == ENOMEM ? SYLVA_ENOMEM : SYLVA_EINVAL, "%s: %s", path,
                           strerror(e));
  cJSON *root = cJSON_ParseWithLength(text, len);
  if (!root) {
    const char *at = cJSON_GetErrorPtr();
    size_t off = at && at >= text && at <= text + len ? (size_t)(at - text) : len;
    free(text);
    return server_fail(err, errlen, SYLVA_EINVAL, "%s: not valid JSON (near byte %zu)", path,
                           off);
  }
  free(text);
  int rc = SYLVA_OK;
  skel_node *nodes = NULL;
  skel_node **by_id = NULL;
  double *node_id = NULL;
  const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
  const cJSON *plants = cJSON_GetObjectItemCaseSensitive(root, "plants");
  if (!cJSON_IsObject(root) || !cJSON_IsString(fmt) ||
      strcmp(fmt->valuestring, "sylva.skeleton/1") != 0) {
    rc = server_fail(
        err, errlen, SYLVA_EINVAL, "%s: not a sylva.skeleton/1 file (its \"format\" is %s%.40s%s)",
        path, cJSON_IsString(fmt) ? "'" : "", cJSON_IsString(fmt) ? fmt->valuestring : "missing",
        cJSON_IsString(fmt) ? "'" : "");
    goto done;
  }
  if (!cJSON_IsArray(plants)) {
    rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: no \"plants\" array", path);
    goto done;
  }
  int models = cJSON_GetArraySize(plants);
  if (models == 0) {
    rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: no plants: an empty model", path);
    goto done;
  }
  if (model > models) {
    rc = server_fail(err, errlen, SYLVA_ERANGE, "%s: no model %d: the file holds %d plant%s",
                         path, model, models, models == 1 ? "" : "s");
    goto done;
  }
  const cJSON *plant = cJSON_GetArrayItem(plants, model ? model - 1 : 0);
  const cJSON *pid = cJSON_GetObjectItemCaseSensitive(plant, "id");
  char plant_name[64];
  if (cJSON_IsString(pid))
    snprintf(plant_name, sizeof plant_name, "%.40s", pid->valuestring);
  else
    snprintf(plant_name, sizeof plant_name, "%d", model ? model : 1);
  const cJSON *stems = cJSON_GetObjectItemCaseSensitive(plant, "stems");
  if (!cJSON_IsArray(stems)) {
    rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: plant '%s': no \"stems\" array", path,
                         plant_name);
    goto done;
  }
  /* Every node of the plant first, then each non-root node's cylinder. */
  size_t n = 0;
  const cJSON *stem;
  cJSON_ArrayForEach(stem, stems) {
    const cJSON *ns = cJSON_GetObjectItemCaseSensitive(stem, "nodes");
    if (!cJSON_IsArray(ns)) {
      rc = server_fail(err, errlen, SYLVA_EINVAL,
                           "%s: plant '%s': a stem without a \"nodes\" array", path, plant_name);
      goto done;
    }
    n += (size_t)cJSON_GetArraySize(ns);
  }
  if (n > (size_t)INT_MAX) {
    rc = server_fail(err, errlen, SYLVA_ETOOBIG, "%s: plant '%s': too many nodes", path,
                         plant_name);
    goto done;
  }
  nodes = calloc(n ? n : 1, sizeof *nodes);
  by_id = calloc(n ? n : 1, sizeof *by_id);
  node_id = calloc(n ? n : 1, sizeof *node_id);
  if (!nodes || !by_id || !node_id) {
    rc = server_fail(err, errlen, SYLVA_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  size_t k = 0;
  int stem_no = 0;
  cJSON_ArrayForEach(stem, stems) {
    stem_no++;
    const cJSON *node;
    int node_no = 0;
    cJSON_ArrayForEach(node, cJSON_GetObjectItemCaseSensitive(stem, "nodes")) {
      node_no++;
      double v[7];
      bool ok = cJSON_IsArray(node) && cJSON_GetArraySize(node) == 7;
      for (int j = 0; ok && j < 7; j++) {
        const cJSON *x = cJSON_GetArrayItem(node, j);
        ok = cJSON_IsNumber(x);
        if (ok) v[j] = x->valuedouble;
      }
      if (!ok || !whole(v[0]) || !whole(v[1])) {
        rc = server_fail(err, errlen, SYLVA_EINVAL,
                             "%s: plant '%s', stem %d, node %d: not [id, parent, x, y, z, radius, "
                             "birth] with whole ids",
                             path, plant_name, stem_no, node_no);
        goto done;
      }
      skel_node *s = &nodes[k];
      s->id = v[0];
      s->parent = v[1];
      memcpy(s->pos, v + 2, sizeof s->pos);
      s->radius = v[5];
      s->cyl = -1;
      by_id[k++] = s;
    }
  }
  qsort(by_id, n, sizeof *by_id, skel_cmp_id);
  for (size_t i = 1; i < n; i++)
    if (by_id[i]->id == by_id[i - 1]->id) {
      rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: plant '%s': two nodes with id %.0f",
                           path, plant_name, by_id[i]->id);
      goto done;
    }
  size_t cyls = 0;
  for (size_t i = 0; i < n; i++)
    if (nodes[i].parent != -1) nodes[i].cyl = (int)cyls++;
  q->models = models;
  if (cyls == 0) {
    rc = server_fail(err, errlen, SYLVA_EINVAL,
                         "%s: plant '%s': no cylinders (no node has a parent)", path, plant_name);
    goto done;
  }
  q->cyl = calloc(cyls, sizeof *q->cyl);
  if (!q->cyl) {
    rc = server_fail(err, errlen, SYLVA_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  for (size_t i = 0; i < n; i++) {
    const skel_node *s = &nodes[i];
    if (s->cyl < 0) continue;
    const skel_node *p = skel_find(by_id, n, s->parent);
    if (!p) {
      rc = server_fail(err, errlen, SYLVA_EINVAL,
                           "%s: plant '%s', node %.0f: its parent %.0f is no node of the plant",
                           path, plant_name, s->id, s->parent);
      goto done;
    }
    sylva_qsm_cylinder *c = &q->cyl[s->cyl];
    double d[3];
    for (int j = 0; j < 3; j++) {
      c->start[j] = p->pos[j];
      d[j] = s->pos[j] - p->pos[j];
    }
    c->length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int j = 0; j < 3; j++) c->axis[j] = c->length > 0 ? d[j] / c->length : 0;
    c->radius = s->radius;
    c->parent = p->cyl; /* -1 under a root node */
    node_id[s->cyl] = s->id;
  }
  q->count = cyls;
  char msg[512];
  skel_names names = {plant_name, node_id};
  rc = sylva__qsm_check_named(q, skel_name, &names, msg, sizeof msg);
  if (rc)
    server_fail(err, errlen, rc, "%s: %s", path, msg);
  else
    sylva__qsm_normalise(q);

done:
  free(nodes);
  free(by_id);
  free(node_id);
  cJSON_Delete(root);
  return rc;
}

/* ---- Reading ---- */

int sylva_qsm_read(const char *path, sylva_qsm_format f, int model, sylva_qsm *q, char *err,
                   size_t errlen) {
  if (err && errlen) err[0] = '\0';
  memset(q, 0, sizeof *q);
  if (model < 0)
    return server_fail(err, errlen, SYLVA_EINVAL,
                           "%s: model %d: models count from 1 (0 for the first)", path, model);
  char buf[SNIFF_BYTES];
  size_t n;
  int e = sniff_read(path, buf, &n);
  if (e)
    return server_fail(err, errlen, e == ENOMEM ? SYLVA_ENOMEM : SYLVA_EINVAL, "%s: %s", path,
                           strerror(e));
  if (f == SYLVA_QSM_UNKNOWN) {
    switch (sniff_bytes(path, buf, n, &f)) {
      case SNIFF_EMPTY:
        return server_fail(err, errlen, SYLVA_EINVAL, "%s: empty file: not a QSM", path);
      case SNIFF_BINARY:
        return server_fail(err, errlen, SYLVA_EINVAL,
                               "%s: not a QSM: binary data, but not a MATLAB MAT-file", path);
      case SNIFF_JSON_OTHER:
        return server_fail(err, errlen, SYLVA_EINVAL,
                               "%s: not a QSM: JSON, but not sylva.skeleton/1", path);
      case SNIFF_FORMAT:
        break;
    }
  }
  int rc;
  switch (f) {
    case SYLVA_QSM_MAT:
      rc = sylva__qsm_read_mat(path, model, q, err, errlen);
      break;
    case SYLVA_QSM_TEXT:
      rc = sylva__qsm_read_text(path, model, q, err, errlen);
      break;
    case SYLVA_QSM_CSV:
      rc = sylva__qsm_read_csv(path, model, q, err, errlen);
      break;
    case SYLVA_QSM_SKELETON:
      rc = read_skeleton(path, model, q, err, errlen);
      break;
    default:
      rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: unknown format %d", path, (int)f);
  }
  if (rc)
    sylva_qsm_free(q);
  else if (!q->has_treedata)
    q->treedata = (sylva_qsm_treedata){NAN, NAN, NAN, NAN, NAN, NAN};
  return rc;
}

/* ---- Writing ---- */

/* Where each cylinder sits in its branch (TreeQSM's PositionInBranch, from 1) and
 * which child continues it (extension, from 1; 0 for none), from branch numbers
 * and parents. pos and ext hold q->count each. */
static int branch_positions(const sylva_qsm *q, int *pos, int *ext) {
  size_t *chain = malloc(q->count * sizeof *chain);
  if (!chain) return SYLVA_ENOMEM;
  for (size_t i = 0; i < q->count; i++) pos[i] = 0, ext[i] = 0;
  for (size_t i = 0; i < q->count; i++) {
    /* Up the branch until a cylinder whose position is known or which starts it. */
    size_t len = 0, j = i;
    while (pos[j] == 0) {
      chain[len++] = j;
      int p = q->cyl[j].parent;
      if (p < 0 || q->cyl[p].branch != q->cyl[j].branch || len == q->count) break;
      j = (size_t)p;
    }
    int at = pos[j]; /* 0 when the chain ends at the branch's first cylinder */
    while (len--) pos[chain[len]] = ++at;
  }
  for (size_t i = 0; i < q->count; i++) {
    int p = q->cyl[i].parent;
    if (p >= 0 && q->cyl[p].branch == q->cyl[i].branch && ext[p] == 0) ext[p] = (int)i + 1;
  }
  free(chain);
  return SYLVA_OK;
}

/* Closes f, turning any write error into a status. */
static int close_written(FILE *f, int rc) {
  if (ferror(f)) rc = SYLVA_EINVAL;
  if (fclose(f) != 0 && !rc) rc = SYLVA_EINVAL;
  return rc;
}

int sylva_qsm_write_text(const sylva_qsm *q, const char *path) {
  /* Unchecked parents would send the branch walk astray. */
  if (sylva_qsm_check(q, NULL, 0)) return SYLVA_EINVAL;
  int *pos = malloc(q->count * sizeof *pos), *ext = malloc(q->count * sizeof *ext);
  if (!pos || !ext || branch_positions(q, pos, ext)) {
    free(pos);
    free(ext);
    return SYLVA_ENOMEM;
  }
  FILE *f = fopen(path, "w");
  if (!f) {
    free(pos);
    free(ext);
    return SYLVA_EINVAL;
  }
  /* TreeQSM's own header row: 13 names over 17 columns. */
  fputs(
      "radius (m)\tlength (m)\tstart_point\taxis_direction\tparent\textension\tbranch\t"
      "branch_order\tposition_in_branch\tmad\tSurfCov\tadded\tUnmodRadius (m)\n",
      f);
  for (size_t i = 0; i < q->count; i++) {
    const sylva_qsm_cylinder *c = &q->cyl[i];
    /* mad and SurfCov are unknown here (0), no cylinder was added to fill a gap,
     * and the unmodified radius is the radius. */
    fprintf(f,
            "%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t%d\t%d\t%d\t%d\t%d\t0\t0\t0\t"
            "%.17g\n",
            c->radius, c->length, c->start[0], c->start[1], c->start[2], c->axis[0], c->axis[1],
            c->axis[2], c->parent + 1, ext[i], c->branch, c->branch_order, pos[i], c->radius);
  }
  free(pos);
  free(ext);
  return close_written(f, SYLVA_OK);
}

int sylva_qsm_write_csv(const sylva_qsm *q, const char *path) {
  if (sylva_qsm_check(q, NULL, 0)) return SYLVA_EINVAL;
  FILE *f = fopen(path, "w");
  if (!f) return SYLVA_EINVAL;
  /* SimpleForest's names for what a cylinder model holds, then the exact length
   * and axis (start + length * axis rounds, so end alone would not give them back). */
  fputs(
      "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius,length,branchID,branchOrder,"
      "axisX,axisY,axisZ\n",
      f);
  for (size_t i = 0; i < q->count; i++) {
    const sylva_qsm_cylinder *c = &q->cyl[i];
    double end[3];
    for (int k = 0; k < 3; k++) end[k] = c->start[k] + c->length * c->axis[k];
    fprintf(f, "%zu,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%.17g,%.17g,%.17g\n",
            i, c->parent, c->start[0], c->start[1], c->start[2], end[0], end[1], end[2], c->radius,
            c->length, c->branch, c->branch_order, c->axis[0], c->axis[1], c->axis[2]);
  }
  return close_written(f, SYLVA_OK);
}
