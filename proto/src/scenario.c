/* Scenario files: strict check, cJSON parse, validation of every rule of
 * scenario.md with errors that name the JSON pointer of the offending value. */
#include "sylva/library.h"
#include "sylva/scenario.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/encode.h"
#include "sylva/json_check.h"
#include "sylva/species_fields.h"
#include "sylva/status.h"
#include "encode_parts.h"
#include "scenario_parts.h"
#include "strbuf.h"

/* ---- error reporting with a JSON pointer (RFC 6901) ---- */

/* Appends one reference token; the pointer is truncated (never overflows) if a key
 * is absurdly long. Control bytes show as '?' so that messages stay printable. */
size_t sylva__ptr_push(sylva__parser *p, const char *token) {
  size_t old = p->plen;
  char *out = p->ptr;
  size_t n = p->plen, cap = sizeof p->ptr - 1;
  if (n < cap) out[n++] = '/';
  const unsigned char *s = (const unsigned char *)token;
  for (; *s && n < cap; s++) {
    if (*s == '~' || *s == '/') {
      if (n + 2 > cap) break;
      out[n++] = '~';
      out[n++] = *s == '~' ? '0' : '1';
    } else {
      out[n++] = *s < 0x20 ? '?' : (char)*s;
    }
  }
  /* A cut inside a UTF-8 sequence drops its first bytes too: messages stay valid UTF-8. */
  if ((*s & 0xC0) == 0x80) {
    while (n > old + 1 && ((unsigned char)out[n - 1] & 0xC0) == 0x80) n--;
    if (n > old + 1 && ((unsigned char)out[n - 1] & 0xC0) == 0xC0) n--;
  }
  out[n] = '\0';
  p->plen = n;
  return old;
}

size_t sylva__ptr_push_index(sylva__parser *p, size_t i) {
  char token[32];
  snprintf(token, sizeof token, "%zu", i);
  return sylva__ptr_push(p, token);
}

void sylva__ptr_pop(sylva__parser *p, size_t old) {
  p->plen = old;
  p->ptr[old] = '\0';
}

/* Writes "<pointer>: <message>" and returns status. */
static int vfail(sylva__parser *p, int status, const char *fmt, va_list ap) {
  if (!p->err || p->errlen == 0) return status;
  int n = snprintf(p->err, p->errlen, "%s: ", p->plen ? p->ptr : "(root)");
  if (n >= 0 && (size_t)n < p->errlen) vsnprintf(p->err + n, p->errlen - (size_t)n, fmt, ap);
  return status;
}

int sylva__fail(sylva__parser *p, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int rc = vfail(p, SYLVA_EINVAL, fmt, ap);
  va_end(ap);
  return rc;
}

/* Fails at the member `key` of the current value (present or not). */
int sylva__fail_at_key(sylva__parser *p, const char *key, const char *fmt, ...) {
  size_t old = sylva__ptr_push(p, key);
  va_list ap;
  va_start(ap, fmt);
  int rc = vfail(p, SYLVA_EINVAL, fmt, ap);
  va_end(ap);
  sylva__ptr_pop(p, old);
  return rc;
}

int sylva__fail_nomem(sylva__parser *p) {
  if (p->err && p->errlen) snprintf(p->err, p->errlen, "out of memory");
  return SYLVA_ENOMEM;
}

/* A user string for a message: quoted, at most about 60 bytes, control bytes as '?'. */
const char *sylva__quote(char buf[80], const char *s) {
  size_t n = 0;
  buf[n++] = '"';
  for (const unsigned char *c = (const unsigned char *)s; *c; c++) {
    if (n >= 64) {
      /* Do not cut a UTF-8 sequence in half. */
      while (n > 1 && ((unsigned char)buf[n - 1] & 0xC0) == 0x80) n--;
      if (n > 1 && ((unsigned char)buf[n - 1] & 0xC0) == 0xC0) n--;
      memcpy(buf + n, "...", 3);
      n += 3;
      break;
    }
    buf[n++] = *c < 0x20 ? '?' : (char)*c;
  }
  buf[n++] = '"';
  buf[n] = '\0';
  return buf;
}

const char *sylva__type_name(const cJSON *item) {
  if (cJSON_IsObject(item)) return "an object";
  if (cJSON_IsArray(item)) return "an array";
  if (cJSON_IsString(item)) return "a string";
  if (cJSON_IsNumber(item)) return "a number";
  if (cJSON_IsBool(item)) return "a boolean";
  if (cJSON_IsNull(item)) return "null";
  return "an invalid value";
}

/* Shortest exact text of a number, for messages. */
const char *sylva__num(char buf[SYLVA_FMT_BUFSIZE], double v) {
  sylva_fmt_shortest(buf, SYLVA_FMT_BUFSIZE, v);
  return buf;
}

/* ---- keys ---- */

static size_t edit_distance(const char *a, const char *b) {
  size_t la = strlen(a), lb = strlen(b);
  if (la > 40 || lb > 40) return 99;
  size_t row[41];
  for (size_t j = 0; j <= lb; j++) row[j] = j;
  for (size_t i = 1; i <= la; i++) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= lb; j++) {
      size_t up = row[j];
      size_t best = diag + (a[i - 1] != b[j - 1]);
      if (up + 1 < best) best = up + 1;
      if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
      row[j] = best;
      diag = up;
    }
  }
  return row[lb];
}

/* Every member of obj must be one of known[] and appear once. */
int sylva__check_keys(sylva__parser *p, const cJSON *obj, const char *const *known, size_t count) {
  for (const cJSON *it = obj->child; it; it = it->next) {
    size_t k = 0;
    while (k < count && strcmp(it->string, known[k]) != 0) k++;
    if (k == count) {
      size_t best = 0, best_d = 99;
      for (size_t i = 0; i < count; i++) {
        size_t d = edit_distance(it->string, known[i]);
        if (d < best_d) best_d = d, best = i;
      }
      if (best_d <= 2 && best_d < strlen(known[best]))
        return sylva__fail_at_key(p, it->string, "unknown key (did you mean \"%s\"?)", known[best]);
      return sylva__fail_at_key(p, it->string, "unknown key");
    }
    for (const cJSON *prev = obj->child; prev != it; prev = prev->next)
      if (strcmp(prev->string, it->string) == 0)
        return sylva__fail_at_key(p, it->string, "duplicate key");
  }
  return 0;
}

/* ---- typed values (the pointer names the value) ---- */

int sylva__want_object(sylva__parser *p, const cJSON *item) {
  return cJSON_IsObject(item)
             ? 0
             : sylva__fail(p, "expected an object, got %s", sylva__type_name(item));
}

int sylva__want_number(sylva__parser *p, const cJSON *item, double *out) {
  if (!cJSON_IsNumber(item))
    return sylva__fail(p, "expected a number, got %s", sylva__type_name(item));
  if (!isfinite(item->valuedouble))
    return sylva__fail(p, "number out of range (not a finite double)");
  *out = item->valuedouble;
  return 0;
}

int sylva__want_string(sylva__parser *p, const cJSON *item, const char **out) {
  if (!cJSON_IsString(item))
    return sylva__fail(p, "expected a string, got %s", sylva__type_name(item));
  *out = item->valuestring;
  return 0;
}

/* A label: 1 to SYLVA_LABEL_MAX - 1 bytes. */
int sylva__want_label(sylva__parser *p, const cJSON *item, char out[SYLVA_LABEL_MAX]) {
  const char *s = "";
  int rc = sylva__want_string(p, item, &s);
  if (rc) return rc;
  size_t n = strlen(s);
  if (n == 0 || n >= SYLVA_LABEL_MAX)
    return sylva__fail(p, "must be 1 to %d bytes long, got %zu", SYLVA_LABEL_MAX - 1, n);
  memcpy(out, s, n + 1);
  return 0;
}

/* A range; an infinite bound means "unbounded on that side". */
typedef struct range {
  double lo, hi;
  bool lo_open, hi_open;
} range;

static bool in_range(double v, range r) {
  if (r.lo_open ? !(v > r.lo) : !(v >= r.lo)) return false;
  if (r.hi_open ? !(v < r.hi) : !(v <= r.hi)) return false;
  return true;
}

static int range_fail(sylva__parser *p, double v, range r) {
  char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE], c[SYLVA_FMT_BUFSIZE];
  if (isinf(r.hi))
    return sylva__fail(p, "must be %s %s, got %s", r.lo_open ? ">" : ">=", sylva__num(a, r.lo),
                       sylva__num(c, v));
  if (isinf(r.lo))
    return sylva__fail(p, "must be %s %s, got %s", r.hi_open ? "<" : "<=", sylva__num(b, r.hi),
                       sylva__num(c, v));
  return sylva__fail(p, "must be in %c%s, %s%c, got %s", r.lo_open ? '(' : '[', sylva__num(a, r.lo),
                     sylva__num(b, r.hi), r.hi_open ? ')' : ']', sylva__num(c, v));
}

static int want_real(sylva__parser *p, const cJSON *item, range r, double *out) {
  double v = 0;
  int rc = sylva__want_number(p, item, &v);
  if (rc) return rc;
  if (!in_range(v, r)) return range_fail(p, v, r);
  *out = v;
  return 0;
}

int sylva__want_integer(sylva__parser *p, const cJSON *item, double lo, double hi, double *out) {
  double v = 0;
  char a[SYLVA_FMT_BUFSIZE];
  int rc = sylva__want_number(p, item, &v);
  if (rc) return rc;
  if (v != floor(v)) return sylva__fail(p, "must be an integer, got %s", sylva__num(a, v));
  range r = {lo, hi, false, false};
  if (!in_range(v, r)) return range_fail(p, v, r);
  *out = v;
  return 0;
}

/* [x, y, z] of finite numbers. */
int sylva__want_vec3(sylva__parser *p, const cJSON *item, double out[3]) {
  if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
    return sylva__fail(p, "expected [x, y, z]");
  int i = 0;
  for (const cJSON *e = item->child; e; e = e->next, i++) {
    size_t old = sylva__ptr_push_index(p, (size_t)i);
    int rc = sylva__want_number(p, e, &out[i]);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  return 0;
}

static const cJSON *member(const cJSON *obj, const char *key) {
  return cJSON_GetObjectItemCaseSensitive(obj, key);
}

int sylva__read_integer(sylva__parser *p, const cJSON *obj, const char *key, double lo,
                        double hi, bool *present, double *out) {
  const cJSON *item = member(obj, key);
  if (present) *present = item != NULL;
  if (!item) return present ? 0 : sylva__fail_at_key(p, key, "required");
  size_t old = sylva__ptr_push(p, key);
  int rc = sylva__want_integer(p, item, lo, hi, out);
  sylva__ptr_pop(p, old);
  return rc;
}

/* ---- species ---- */

#define UNBOUNDED HUGE_VAL
static const range R_POSITIVE = {0, UNBOUNDED, true, false};

typedef struct species_field {
  const char *key;
  size_t offset;
  bool integer; /* an int field; else a double */
  range r;
  bool scaled;  /* a field of real species (place 37 and up in species_fields.h):
                   written in the canonical form only when not at its default */
  double dflt;  /* its default */
} species_field;

/* The first snapshot place of the fields of real species (species_fields.h). */
#define FIRST_SCALED_PLACE 37

/* The scalar fields of a species, in sylva/species_fields.h's order: top-level keys
 * of a species object, and keys of its "markers" object. IN(group, wanted, ...)
 * keeps its arguments for a field of the wanted group. */
#define IN_species_species(...) __VA_ARGS__
#define IN_species_markers(...)
#define IN_markers_species(...)
#define IN_markers_markers(...) __VA_ARGS__
#define IN(group, wanted, ...) IN_##group##_##wanted(__VA_ARGS__)
#define IS_INT_double false
#define IS_INT_int true
#define FIELD(name, type, def, lo, hi, bounds, snap)                       \
  {#name,                                                                  \
   offsetof(sylva_species_def, name),                                      \
   IS_INT_##type,                                                          \
   {lo, hi, ((bounds) & SYLVA_FIELD_MIN_EXCLUSIVE) != 0,                   \
    ((bounds) & SYLVA_FIELD_MAX_EXCLUSIVE) != 0},                          \
   (snap) >= FIRST_SCALED_PLACE,                                           \
   def},
#define SPECIES_FIELD(name, type, def, lo, hi, bounds, group, snap) \
  IN(group, species, FIELD(name, type, def, lo, hi, bounds, snap))
#define MARKER_FIELD(name, type, def, lo, hi, bounds, group, snap) \
  IN(group, markers, FIELD(name, type, def, lo, hi, bounds, snap))
#define SPECIES_KEY(name, type, def, lo, hi, bounds, group, snap) IN(group, species, #name, )

static const species_field species_fields[] = {SYLVA_SPECIES_FIELDS(SPECIES_FIELD)};
static const species_field marker_fields[] = {SYLVA_SPECIES_FIELDS(MARKER_FIELD)};
/* Every key of a species object: the ones the list does not hold, then the list's. */
static const char *const species_keys[] = {"preset", "growth", "allocation", "tropism",
                                           "markers", SYLVA_SPECIES_FIELDS(SPECIES_KEY)};

#undef IN_species_species
#undef IN_species_markers
#undef IN_markers_species
#undef IN_markers_markers
#undef IN
#undef IS_INT_double
#undef IS_INT_int
#undef FIELD
#undef SPECIES_FIELD
#undef MARKER_FIELD
#undef SPECIES_KEY

/* The one field written as a string: a colour "#rrggbb" (0xRRGGBB in the def). */
static bool is_colour(const species_field *f) { return strcmp(f->key, "leaf_colour") == 0; }

static int want_colour(sylva__parser *p, const cJSON *item, double *v) {
  const char *s = "";
  int rc = sylva__want_string(p, item, &s);
  if (rc) return rc;
  bool ok = strlen(s) == 7 && s[0] == '#';
  for (int i = 1; ok && i < 7; i++) ok = isxdigit((unsigned char)s[i]) != 0;
  if (!ok) {
    char q[80];
    return sylva__fail(p, "must be a colour \"#rrggbb\" (six hex digits), got %s",
                       sylva__quote(q, s));
  }
  *v = (double)strtol(s + 1, NULL, 16);
  return 0;
}

static int set_fields(sylva__parser *p, const cJSON *obj, const species_field *fields, size_t count,
                      sylva_species_def *def) {
  for (size_t i = 0; i < count; i++) {
    const cJSON *item = member(obj, fields[i].key);
    if (!item) continue;
    size_t old = sylva__ptr_push(p, fields[i].key);
    double v = 0;
    int rc = is_colour(&fields[i])   ? want_colour(p, item, &v)
             : fields[i].integer ? sylva__want_integer(p, item, fields[i].r.lo, fields[i].r.hi, &v)
                                 : want_real(p, item, fields[i].r, &v);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
    char *at = (char *)def + fields[i].offset;
    if (fields[i].integer) {
      int iv = (int)v;
      memcpy(at, &iv, sizeof iv);
    } else {
      memcpy(at, &v, sizeof v);
    }
  }
  return 0;
}

static const char *const equation_params[SYLVA_EQ_COUNT][3] = {
    [SYLVA_EQ_LOGISTIC] = {"X0", "Xm", "r"},
    [SYLVA_EQ_BERTALANFFY] = {"beta1", "beta2", NULL},
    [SYLVA_EQ_WEIBULL] = {"omega1", "omega2", "omega3"},
    [SYLVA_EQ_GOMPERTZ] = {"A", "B", "C"},
};

static const char *equation_param_list(sylva_equation_kind kind) {
  switch (kind) {
  case SYLVA_EQ_LOGISTIC: return "X0, Xm, r";
  case SYLVA_EQ_BERTALANFFY: return "beta1, beta2";
  case SYLVA_EQ_WEIBULL: return "omega1, omega2, omega3";
  default: return "A, B, C";
  }
}

/* "growth": the equation may be left out to override parameters of the base
 * (preset or default) equation; a different equation needs all its parameters. */
static int parse_growth(sylva__parser *p, const cJSON *obj, sylva_equation *eq) {
  int rc = sylva__want_object(p, obj);
  if (rc) return rc;
  static const char *const keys[] = {"equation", "X0",     "Xm",     "r", "beta1", "beta2",
                                     "omega1",   "omega2", "omega3", "A", "B",     "C"};
  if ((rc = sylva__check_keys(p, obj, keys, sizeof keys / sizeof keys[0]))) return rc;
  sylva_equation_kind kind = eq->kind;
  const cJSON *name = member(obj, "equation");
  if (name) {
    size_t old = sylva__ptr_push(p, "equation");
    const char *s = "";
    rc = sylva__want_string(p, name, &s);
    int k = 0;
    while (!rc && k < SYLVA_EQ_COUNT && strcmp(s, sylva_equation_name((sylva_equation_kind)k)) != 0)
      k++;
    if (!rc && k == SYLVA_EQ_COUNT) {
      char q[80];
      rc = sylva__fail(p, "unknown equation %s (known: logistic, bertalanffy, weibull, gompertz)",
                       sylva__quote(q, s));
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
    kind = (sylva_equation_kind)k;
  }
  const char *const *names = equation_params[kind];
  for (const cJSON *it = obj->child; it; it = it->next) {
    if (strcmp(it->string, "equation") == 0) continue;
    bool ours = false;
    for (int i = 0; i < 3; i++)
      if (names[i] && strcmp(names[i], it->string) == 0) ours = true;
    if (!ours)
      return sylva__fail_at_key(p, it->string, "not a parameter of the %s equation (%s)",
                                sylva_equation_name(kind), equation_param_list(kind));
  }
  sylva_equation out = {kind, {0, 0, 0}};
  for (int i = 0; i < 3 && names[i]; i++) {
    const cJSON *item = member(obj, names[i]);
    if (!item) {
      if (kind != eq->kind)
        return sylva__fail_at_key(p, names[i], "required by the %s equation",
                                  sylva_equation_name(kind));
      out.p[i] = eq->p[i];
      continue;
    }
    size_t old = sylva__ptr_push(p, names[i]);
    rc = want_real(p, item, R_POSITIVE, &out.p[i]);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE];
  if (kind == SYLVA_EQ_LOGISTIC && !(out.p[0] < out.p[1])) {
    if (member(obj, "X0"))
      return sylva__fail_at_key(p, "X0", "must be < Xm (%s), got %s", sylva__num(a, out.p[1]),
                                sylva__num(b, out.p[0]));
    return sylva__fail_at_key(p, "Xm", "must be > X0 (%s), got %s", sylva__num(a, out.p[0]),
                              sylva__num(b, out.p[1]));
  }
  if (sylva_equation_limit(&out) > 1e6)
    return sylva__fail(p, "the limit of the equation is %s internodes; at most 1e6 are allowed",
                       sylva__num(a, sylva_equation_limit(&out)));
  *eq = out;
  return 0;
}

static int parse_markers(sylva__parser *p, const cJSON *obj, sylva_species_def *def) {
  static const char *const keys[] = {"m0", "m_min", "cone_angle", "cone_radius"};
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, keys, 4);
  if (!rc) rc = set_fields(p, obj, marker_fields, sizeof marker_fields / sizeof marker_fields[0], def);
  if (rc) return rc;
  if (def->m_min > def->m0) {
    if (member(obj, "m_min"))
      return sylva__fail_at_key(p, "m_min", "must be <= m0 (%d), got %d", def->m0, def->m_min);
    return sylva__fail_at_key(p, "m0", "must be >= m_min (%d), got %d", def->m_min, def->m0);
  }
  return 0;
}

static int parse_species(sylva__parser *p, const cJSON *obj, sylva_species_def *out) {
  int rc = sylva__want_object(p, obj);
  if (!rc)
    rc = sylva__check_keys(p, obj, species_keys, sizeof species_keys / sizeof species_keys[0]);
  if (rc) return rc;
  sylva_species_def def = sylva_default_species_def();
  const cJSON *item = member(obj, "preset");
  if (item) {
    size_t old = sylva__ptr_push(p, "preset");
    const char *name = "";
    rc = sylva__want_string(p, item, &name);
    if (!rc && sylva_preset_find(name, &def) != 0) {
      char list[1024] = "", q[80];
      size_t n = 0;
      if (strncmp(name, SYLVA_LIBRARY_PREFIX, strlen(SYLVA_LIBRARY_PREFIX)) == 0) {
        /* a library name: the library's, and how to make any other */
        sylva_library_names(list, sizeof list);
        rc = sylva__fail(p, "unknown library species %s (the library: %s; `sylva fit --utdb "
                         "REGION:CODE` calibrates any species of the Urban Tree Database)",
                         sylva__quote(q, name), list);
      } else {
        for (int i = 0; i < sylva_preset_count() && n < sizeof list; i++)
          n += (size_t)snprintf(list + n, sizeof list - n, "%s%s", i ? ", " : "", sylva_preset_name(i));
        rc = sylva__fail(p, "unknown preset %s (known: %s; and the library's utdb:REGION:CODE, "
                         "`sylva species`)", sylva__quote(q, name), list);
      }
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  rc = set_fields(p, obj, species_fields, sizeof species_fields / sizeof species_fields[0], &def);
  if (rc) return rc;
  if ((item = member(obj, "growth"))) {
    size_t old = sylva__ptr_push(p, "growth");
    rc = parse_growth(p, item, &def.growth);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  if ((item = member(obj, "allocation"))) {
    size_t old = sylva__ptr_push(p, "allocation");
    const char *s = "";
    rc = sylva__want_string(p, item, &s);
    if (!rc) {
      char q[80];
      if (strcmp(s, "lgtm") == 0) def.allocation = SYLVA_ALLOC_LGTM;
      else if (strcmp(s, "none") == 0) def.allocation = SYLVA_ALLOC_NONE;
      else
        rc = sylva__fail(p, "must be \"lgtm\" or \"none\", got %s", sylva__quote(q, s));
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  if ((item = member(obj, "tropism"))) {
    size_t old = sylva__ptr_push(p, "tropism");
    double v[3] = {0, 0, 0};
    rc = sylva__want_vec3(p, item, v);
    for (int i = 0; !rc && i < 3; i++)
      if (fabs(v[i]) > 1000) {
        size_t o2 = sylva__ptr_push_index(p, (size_t)i);
        rc = range_fail(p, v[i], (range){-1000, 1000, false, false});
        sylva__ptr_pop(p, o2);
      }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
    memcpy(def.tropism, v, sizeof v);
  }
  if ((item = member(obj, "markers"))) {
    size_t old = sylva__ptr_push(p, "markers");
    rc = parse_markers(p, item, &def);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  if (!(def.b_max >= def.b_min)) {
    char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE];
    if (member(obj, "b_max"))
      return sylva__fail_at_key(p, "b_max", "must be >= b_min (%s), got %s",
                                sylva__num(a, def.b_min), sylva__num(b, def.b_max));
    return sylva__fail_at_key(p, "b_min", "must be <= b_max (%s), got %s", sylva__num(a, def.b_max),
                              sylva__num(b, def.b_min));
  }
  if (def.biomass_form == 1 && !(def.wood_density > 0))
    return sylva__fail_at_key(p, "wood_density",
                              "must be above 0 with biomass_form 1 (a volume allometry), got %s",
                              sylva__num((char[SYLVA_FMT_BUFSIZE]){0}, def.wood_density));
  /* The initial trunk follows the final growth equation unless given. */
  if (!member(obj, "initial_nodes")) {
    if (def.growth.kind == SYLVA_EQ_LOGISTIC) {
      double x0 = floor(def.growth.p[0] + 0.5);
      def.initial_nodes = x0 < 1 ? 1 : x0 > 1000 ? 1000 : (int)x0;
    } else {
      def.initial_nodes = 2;
    }
  }
  const char *field = NULL;
  if (sylva_species_check(&def, &field) != 0)
    return sylva__fail_at_key(p, field ? field : "?", "value out of range");
  *out = def;
  return 0;
}

/* ---- the scenario ---- */


static int cmp_id_ref(const void *a, const void *b) {
  const sylva__id_ref *x = a, *y = b;
  int c = strcmp(x->id, y->id);
  return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* Finds the first repeated id: *first and *second are the indices of its first
 * occurrence and of the earliest repetition; false if every id is unique. */
bool sylva__find_duplicate(sylva__id_ref *refs, int count, int *first, int *second) {
  qsort(refs, (size_t)count, sizeof *refs, cmp_id_ref);
  bool found = false;
  for (int i = 1; i < count; i++) {
    if (strcmp(refs[i - 1].id, refs[i].id) != 0) continue;
    int group = i - 1;
    while (group > 0 && strcmp(refs[group - 1].id, refs[i].id) == 0) group--;
    if (!found || refs[i].index < *second) {
      *first = refs[group].index;
      *second = refs[i].index;
      found = true;
    }
  }
  return found;
}

static int cmp_id_ref_name(const void *key, const void *elem) {
  return strcmp((const char *)key, ((const sylva__id_ref *)elem)->id);
}

/* The "from" object of a plant: {"file", "format"?, "model"?, "age"?}. */
static int parse_from(sylva__parser *p, const cJSON *obj, sylva_scenario_plant *pl) {
  static const char *const keys[] = {"file", "format", "model", "age"};
  size_t old = sylva__ptr_push(p, "from");
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, keys, 4);
  if (!rc && !member(obj, "file")) rc = sylva__fail_at_key(p, "file", "required");
  const char *file = "";
  if (!rc) {
    size_t o2 = sylva__ptr_push(p, "file");
    rc = sylva__want_string(p, member(obj, "file"), &file);
    size_t n = strlen(file);
    if (!rc && (n == 0 || n > 4096)) rc = sylva__fail(p, "must be 1 to 4096 bytes long, got %zu", n);
    if (!rc && !(pl->from_file = strdup(file))) rc = sylva__fail_nomem(p);
    sylva__ptr_pop(p, o2);
  }
  if (!rc && member(obj, "format")) {
    size_t o2 = sylva__ptr_push(p, "format");
    const char *f = "";
    rc = sylva__want_string(p, member(obj, "format"), &f);
    if (!rc && strcmp(f, "mat") && strcmp(f, "text") && strcmp(f, "csv") && strcmp(f, "skeleton")) {
      char q[80];
      rc = sylva__fail(p, "unknown format %s (known: mat, text, csv, skeleton)", sylva__quote(q, f));
    }
    if (!rc) snprintf(pl->from_format, sizeof pl->from_format, "%s", f);
    sylva__ptr_pop(p, o2);
  }
  double v = 0;
  bool given;
  if (!rc) rc = sylva__read_integer(p, obj, "model", 1, 100000, &given, &v);
  if (!rc) pl->from_model = given ? (int)v : 0;
  if (!rc) rc = sylva__read_integer(p, obj, "age", 0, SYLVA_MAX_AGE, &given, &v);
  if (!rc) pl->from_age = given ? (int)v : -1;
  sylva__ptr_pop(p, old);
  return rc;
}

/* Adds to s->species each library species ("utdb:REGION:CODE") that a plant of the
 * array `plants` names and the species map lacks, its def the library's (docs/scenario.md,
 * "Plants"). An unknown library name is left for the plant's own check to name. */
static int add_library_species(sylva__parser *p, const cJSON *plants, sylva_scenario *s) {
  const size_t prefix = strlen(SYLVA_LIBRARY_PREFIX);
  int i = 0;
  for (const cJSON *pl = plants->child; pl; pl = pl->next, i++) {
    const cJSON *sp = cJSON_IsObject(pl) ? member(pl, "species") : NULL;
    const char *name = cJSON_IsString(sp) ? sp->valuestring : NULL;
    if (!name || strncmp(name, SYLVA_LIBRARY_PREFIX, prefix) != 0 || strlen(name) >= SYLVA_LABEL_MAX)
      continue;
    bool known = false;
    for (int k = 0; k < s->species_count && !known; k++) known = strcmp(s->species[k].name, name) == 0;
    sylva_species_def def = sylva_default_species_def();
    if (known || sylva_preset_find(name, &def) != 0) continue;
    if (s->species_count == SYLVA_SCENARIO_MAX_SPECIES) {
      size_t old = sylva__ptr_push_index(p, (size_t)i);
      int rc = sylva__fail_at_key(p, "species", "%d species; at most %d are allowed",
                                  s->species_count + 1, SYLVA_SCENARIO_MAX_SPECIES);
      sylva__ptr_pop(p, old);
      return rc;
    }
    sylva_scenario_species *grown = realloc(s->species, ((size_t)s->species_count + 1) * sizeof *grown);
    if (!grown) return sylva__fail_nomem(p);
    s->species = grown;
    memset(&grown[s->species_count], 0, sizeof *grown);
    memcpy(grown[s->species_count].name, name, strlen(name) + 1);
    grown[s->species_count++].def = def;
  }
  return 0;
}

/* by_name: the species sorted by name, for lookups in O(log n). */
int sylva__parse_plant(sylva__parser *p, const cJSON *obj, const sylva__id_ref *by_name,
                       int species_count, int *stem_count, sylva_scenario_plant *pl,
                       const char **species_name) {
  static const char *const keys[] = {"id", "species", "roots", "age", "from"};
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, keys, 5);
  if (rc) return rc;
  pl->from_age = -1;
  if (member(obj, "from")) {
    /* a file is read only from a scenario, never for a message over the wire */
    if (!by_name) return sylva__fail_at_key(p, "from", "measured trees come only from a scenario's files");
    rc = parse_from(p, member(obj, "from"), pl);
    if (rc) return rc;
  }
  for (int i = 0; i < 3; i++) /* age is optional */
    if (!member(obj, keys[i])) return sylva__fail_at_key(p, keys[i], "required");
  size_t old = sylva__ptr_push(p, "id");
  rc = sylva__want_label(p, member(obj, "id"), pl->id);
  sylva__ptr_pop(p, old);
  if (rc) return rc;

  old = sylva__ptr_push(p, "species");
  const char *name = "";
  rc = sylva__want_string(p, member(obj, "species"), &name);
  pl->species = -1;
  if (!rc && !by_name) {
    size_t n = strlen(name);
    if (n == 0 || n >= SYLVA_LABEL_MAX)
      rc = sylva__fail(p, "must be 1 to %d bytes long, got %zu", SYLVA_LABEL_MAX - 1, n);
    else if (species_name)
      *species_name = name;
  } else if (!rc) {
    const sylva__id_ref *found = species_count ? bsearch(name, by_name, (size_t)species_count,
                                                         sizeof *by_name, cmp_id_ref_name)
                                               : NULL;
    if (found) {
      pl->species = found->index;
    } else {
      char q[80];
      if (strncmp(name, SYLVA_LIBRARY_PREFIX, strlen(SYLVA_LIBRARY_PREFIX)) == 0)
        rc = sylva__fail(p, "unknown species %s (not a key of %.*s/species, nor a library species: "
                         "`sylva species` lists them)", sylva__quote(q, name), (int)p->base, p->ptr);
      else
        rc = sylva__fail(p, "unknown species %s (not a key of %.*s/species)", sylva__quote(q, name),
                         (int)p->base, p->ptr);
    }
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;

  old = sylva__ptr_push(p, "roots");
  const cJSON *roots = member(obj, "roots");
  int count = cJSON_IsArray(roots) ? cJSON_GetArraySize(roots) : 0;
  if (!cJSON_IsArray(roots))
    rc = sylva__fail(p, "expected an array of [x, y, z], got %s", sylva__type_name(roots));
  else if (count == 0)
    rc = sylva__fail(p, "must hold at least one root");
  else if (count > SYLVA_SCENARIO_MAX_ROOTS)
    rc = sylva__fail(p, "%d roots; a plant may have at most %d", count, SYLVA_SCENARIO_MAX_ROOTS);
  else if (*stem_count > SYLVA_MAX_STEMS - count)
    rc = sylva__fail(p, "too many stems: a world holds at most %d", SYLVA_MAX_STEMS);
  if (!rc && !(pl->roots = malloc((size_t)count * sizeof *pl->roots))) rc = sylva__fail_nomem(p);
  int i = 0;
  for (const cJSON *r = rc ? NULL : roots->child; r && !rc; r = r->next, i++) {
    size_t o2 = sylva__ptr_push_index(p, (size_t)i);
    rc = sylva__want_vec3(p, r, pl->roots[i]);
    sylva__ptr_pop(p, o2);
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  pl->root_count = count;
  *stem_count += count;
  double age = 0; /* when absent */
  bool given;
  rc = sylva__read_integer(p, obj, "age", 0, SYLVA_MAX_AGE, &given, &age);
  pl->age = (int)age;
  if (!rc && pl->from_file && given)
    rc = sylva__fail_at_key(p, "age", "a measured tree's age goes in from/age");
  if (!rc && pl->from_file && count != 1)
    rc = sylva__fail_at_key(p, "roots", "a measured tree stands at one root, got %d", count);
  return rc;
}

/* "1.2e12": two significant digits, no '+' or leading zeros in the exponent. */
static const char *sci(char buf[48], double v) {
  char tmp[32];
  snprintf(tmp, sizeof tmp, "%.1e", v);
  char *e = strchr(tmp, 'e');
  if (!e) {
    snprintf(buf, 48, "%s", tmp);
    return buf;
  }
  *e = '\0';
  int exponent = atoi(e + 1);
  size_t n = strlen(tmp);
  if (n >= 2 && strcmp(tmp + n - 2, ".0") == 0) tmp[n - 2] = '\0';
  snprintf(buf, 48, "%se%d", tmp, exponent);
  return buf;
}

static int fail_status(sylva__parser *p, int status, const char *fmt, ...) SYLVA__PRINTF_LIKE(3, 4);
static int fail_status(sylva__parser *p, int status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int rc = vfail(p, status, fmt, ap);
  va_end(ap);
  return rc;
}

static sylva_world_def world_def_of(const sylva_scenario *s, double voxel) {
  sylva_world_def def = sylva_default_world_def();
  memcpy(def.min, s->world_min, sizeof def.min);
  memcpy(def.max, s->world_max, sizeof def.max);
  def.voxel = voxel;
  def.seed = s->seed;
  def.stand_area = s->stand_area;
  return def;
}

/* Refuses a world whose voxels would not fit and names a voxel edge that would. */
static int check_world_size(sylva__parser *p, const sylva_scenario *s) {
  sylva_world_def def = world_def_of(s, s->voxel);
  int rc = sylva_world_def_check(&def);
  if (rc == 0) return 0;
  size_t old = sylva__ptr_push(p, "world");
  if (rc != SYLVA_ETOOBIG) {
    rc = fail_status(p, rc, "%s", sylva_strerror(rc));
    sylva__ptr_pop(p, old);
    return rc;
  }
  double count = 1, volume = 1;
  for (int i = 0; i < 3; i++) {
    double extent = s->world_max[i] - s->world_min[i];
    count *= ceil(extent / s->voxel);
    volume *= extent;
  }
  /* The smallest edge with two significant digits that the core accepts. */
  double edge = cbrt(volume / SYLVA_MAX_VOXELS);
  double unit = pow(10.0, floor(log10(edge)) - 1);
  double steps = ceil(edge / unit - 1e-9);
  for (int tries = 0; tries < 1000; tries++) {
    char two[32];
    snprintf(two, sizeof two, "%.1e", steps * unit);
    def.voxel = strtod(two, NULL);
    if (sylva_world_def_check(&def) != SYLVA_ETOOBIG) break;
    steps += 1;
  }
  char a[48], b[48], v[SYLVA_FMT_BUFSIZE], e[SYLVA_FMT_BUFSIZE];
  rc = fail_status(
      p, SYLVA_ETOOBIG, "%s voxels at voxel %s m exceed the limit of %s; use \"voxel\" >= %s",
      sci(a, count), sylva__num(v, s->voxel), sci(b, SYLVA_MAX_VOXELS), sylva__num(e, def.voxel));
  sylva__ptr_pop(p, old);
  return rc;
}

static void scenario_free_parts(sylva_scenario *s) {
  if (!s) return;
  free(s->name);
  free(s->species);
  for (int i = 0; s->plants && i < s->plant_count; i++) {
    free(s->plants[i].roots);
    free(s->plants[i].from_file);
    free(s->plants[i].nodes);
  }
  free(s->plants);
  for (int i = 0; s->obstacles && i < s->obstacle_count; i++) sylva_scenario_obstacle_clear(&s->obstacles[i]);
  free(s->obstacles);
  free(s->management);
  free(s);
}

void sylva_scenario_free(sylva_scenario *s) { scenario_free_parts(s); }

/* A plant older than its planting needs a species that counts in years. */
static int check_age(sylva__parser *p, const sylva_scenario_plant *pl,
                     const sylva_scenario_species *sp) {
  char q[80];
  if (pl->age == 0 || sp->def.years) return 0;
  return sylva__fail_at_key(p, "age", "species %s has no time scale (years)",
                            sylva__quote(q, sp->name));
}

/* The site's frame: {"crs": "EPSG:32618", "origin": [easting, northing]}. */
static int parse_site(sylva__parser *p, const cJSON *obj, sylva_scenario *s) {
  static const char *const keys[] = {"crs", "origin"};
  size_t old = sylva__ptr_push(p, "site");
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, keys, 2);
  for (int i = 0; !rc && i < 2; i++)
    if (!member(obj, keys[i])) rc = sylva__fail_at_key(p, keys[i], "required");
  if (!rc) {
    size_t o2 = sylva__ptr_push(p, "crs");
    const char *crs = "";
    rc = sylva__want_string(p, member(obj, "crs"), &crs);
    size_t n = strlen(crs);
    if (!rc && (n == 0 || n >= sizeof s->site_crs))
      rc = sylva__fail(p, "must be 1 to %zu bytes long (\"EPSG:32618\"), got %zu", sizeof s->site_crs - 1, n);
    if (!rc) memcpy(s->site_crs, crs, n + 1);
    sylva__ptr_pop(p, o2);
  }
  if (!rc) {
    size_t o2 = sylva__ptr_push(p, "origin");
    const cJSON *o = member(obj, "origin");
    if (!cJSON_IsArray(o) || cJSON_GetArraySize(o) != 2 || !cJSON_IsNumber(o->child) ||
        !cJSON_IsNumber(o->child->next) || !isfinite(o->child->valuedouble) ||
        !isfinite(o->child->next->valuedouble))
      rc = sylva__fail(p, "expected [x, y], finite, in the CRS's units");
    else {
      s->site_origin[0] = o->child->valuedouble;
      s->site_origin[1] = o->child->next->valuedouble;
    }
    sylva__ptr_pop(p, o2);
  }
  sylva__ptr_pop(p, old);
  return rc;
}

static const char *const top_keys[] = {"format",  "name",   "seed",      "iterations",
                                       "start_year", "world", "species", "plants",
                                       "obstacles", "management", "light", "site",
                                       "stand_area"};

static int parse_top(sylva__parser *p, const cJSON *root, unsigned flags, sylva_scenario *s) {
  int rc = sylva__want_object(p, root);
  if (rc) return rc;
  const cJSON *item = member(root, "format");
  char q[80];
  if (!item)
    return sylva__fail_at_key(p, "format", "required: \"%s\" (is this a scenario file?)",
                              SYLVA_SCENARIO_FORMAT);
  if (!cJSON_IsString(item) || strcmp(item->valuestring, SYLVA_SCENARIO_FORMAT) != 0) {
    if (cJSON_IsString(item))
      return sylva__fail_at_key(p, "format", "expected \"%s\", got %s", SYLVA_SCENARIO_FORMAT,
                                sylva__quote(q, item->valuestring));
    return sylva__fail_at_key(p, "format", "expected \"%s\", got %s", SYLVA_SCENARIO_FORMAT,
                              sylva__type_name(item));
  }
  if ((rc = sylva__check_keys(p, root, top_keys, sizeof top_keys / sizeof top_keys[0]))) return rc;

  const char *name = "untitled";
  size_t old;
  if ((item = member(root, "name"))) {
    old = sylva__ptr_push(p, "name");
    rc = sylva__want_string(p, item, &name);
    if (!rc && (name[0] == '\0' || strlen(name) > SYLVA_SCENARIO_NAME_MAX))
      rc = sylva__fail(p, "must be 1 to %d bytes long, got %zu", SYLVA_SCENARIO_NAME_MAX,
                       strlen(name));
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  if (!(s->name = strdup(name))) return sylva__fail_nomem(p);

  double v = 0;
  /* each keeps its default when not given */
  bool given;
  v = 1;
  if ((rc = sylva__read_integer(p, root, "seed", 0, SYLVA_SCENARIO_SEED_MAX, &given, &v)))
    return rc;
  s->seed = (uint64_t)v;
  v = 40;
  if ((rc = sylva__read_integer(p, root, "iterations", 1, SYLVA_SCENARIO_MAX_ITERATIONS, &given,
                                &v)))
    return rc;
  s->iterations = (int)v;
  v = 0; /* none */
  if ((rc = sylva__read_integer(p, root, "start_year", 1, SYLVA_SCENARIO_MAX_YEAR, &given, &v)))
    return rc;
  s->start_year = (int)v;
  if ((item = member(root, "stand_area"))) { /* m^2 (docs/model.md, "Stands") */
    old = sylva__ptr_push(p, "stand_area");
    rc = want_real(p, item, R_POSITIVE, &s->stand_area);
    if (!rc && s->stand_area > 1e12)
      rc = sylva__fail(p, "must be at most 1e12 m2, got %g", s->stand_area);
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }

  /* species, before the plants that name them */
  if ((item = member(root, "species"))) {
    old = sylva__ptr_push(p, "species");
    rc = sylva__want_object(p, item);
    int count = rc ? 0 : cJSON_GetArraySize(item);
    if (!rc && count > SYLVA_SCENARIO_MAX_SPECIES)
      rc = sylva__fail(p, "%d species; at most %d are allowed", count, SYLVA_SCENARIO_MAX_SPECIES);
    if (!rc && count && !(s->species = calloc((size_t)count, sizeof *s->species)))
      rc = sylva__fail_nomem(p);
    for (const cJSON *sp = rc ? NULL : item->child; sp && !rc; sp = sp->next) {
      size_t o2 = sylva__ptr_push(p, sp->string);
      size_t n = strlen(sp->string);
      if (n == 0 || n >= SYLVA_LABEL_MAX)
        rc = sylva__fail(p, "a species name must be 1 to %d bytes long, got %zu",
                         SYLVA_LABEL_MAX - 1, n);
      for (int i = 0; !rc && i < s->species_count; i++)
        if (strcmp(s->species[i].name, sp->string) == 0) rc = sylva__fail(p, "duplicate key");
      if (!rc) rc = parse_species(p, sp, &s->species[s->species_count].def);
      if (!rc) memcpy(s->species[s->species_count++].name, sp->string, n + 1);
      sylva__ptr_pop(p, o2);
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }

  /* library species named by plants directly ("species": "utdb:NoEast:PLAC"), with
   * no entry in the species map: each becomes one, in the order first named */
  if (!rc && (item = member(root, "plants")) && cJSON_IsArray(item))
    rc = add_library_species(p, item, s);
  if (rc) return rc;

  /* world: the box now, the voxel once the plants are known */
  if (!(item = member(root, "world")))
    return sylva__fail_at_key(p, "world", "required: {\"min\": [x, y, z], \"max\": [x, y, z]}");
  old = sylva__ptr_push(p, "world");
  static const char *const world_keys[] = {"min", "max", "voxel"};
  rc = sylva__want_object(p, item);
  if (!rc) rc = sylva__check_keys(p, item, world_keys, 3);
  if (!rc && !member(item, "min")) rc = sylva__fail_at_key(p, "min", "required");
  if (!rc && !member(item, "max")) rc = sylva__fail_at_key(p, "max", "required");
  if (!rc) {
    size_t o2 = sylva__ptr_push(p, "min");
    rc = sylva__want_vec3(p, member(item, "min"), s->world_min);
    sylva__ptr_pop(p, o2);
  }
  if (!rc) {
    size_t o2 = sylva__ptr_push(p, "max");
    rc = sylva__want_vec3(p, member(item, "max"), s->world_max);
    for (int i = 0; !rc && i < 3; i++)
      if (!(s->world_max[i] > s->world_min[i])) {
        char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE];
        rc = sylva__fail(p, "must be greater than %.*s/world/min on every axis (%c: %s <= %s)",
                         (int)p->base, p->ptr, "xyz"[i], sylva__num(a, s->world_max[i]),
                         sylva__num(b, s->world_min[i]));
      }
    sylva__ptr_pop(p, o2);
  }
  const cJSON *voxel = rc ? NULL : member(item, "voxel");
  if (voxel) {
    size_t o2 = sylva__ptr_push(p, "voxel");
    rc = want_real(p, voxel, R_POSITIVE, &s->voxel);
    sylva__ptr_pop(p, o2);
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;

  const bool need_plants = flags & SYLVA_SCENARIO_NEED_PLANTS;
  if (!(item = member(root, "plants")) && need_plants)
    return sylva__fail_at_key(p, "plants", "required");
  if (item) {
    old = sylva__ptr_push(p, "plants");
    int count = cJSON_IsArray(item) ? cJSON_GetArraySize(item) : 0;
    if (!cJSON_IsArray(item))
      rc = sylva__fail(p, "expected an array, got %s", sylva__type_name(item));
    else if (count > SYLVA_MAX_STEMS)
      rc = sylva__fail(p, "%d plants; a world holds at most %d stems", count, SYLVA_MAX_STEMS);
    else if (count == 0 && need_plants)
      rc = sylva__fail(p, "nothing to grow (the list is empty)");
    if (!rc && count && !(s->plants = calloc((size_t)count, sizeof *s->plants)))
      rc = sylva__fail_nomem(p);
    sylva__id_ref *by_name = NULL;
    if (!rc && count && !(by_name = malloc(((size_t)s->species_count + 1) * sizeof *by_name)))
      rc = sylva__fail_nomem(p);
    if (by_name) {
      for (int k = 0; k < s->species_count; k++)
        by_name[k] = (sylva__id_ref){s->species[k].name, k};
      qsort(by_name, (size_t)s->species_count, sizeof *by_name, cmp_id_ref);
    }
    int i = 0;
    for (const cJSON *pl = rc ? NULL : item->child; pl && !rc; pl = pl->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      s->plant_count = i + 1; /* so that a partial plant is freed */
      rc =
          sylva__parse_plant(p, pl, by_name, s->species_count, &s->stem_count, &s->plants[i], NULL);
      if (!rc) rc = check_age(p, &s->plants[i], &s->species[s->plants[i].species]);
      sylva__ptr_pop(p, o2);
    }
    free(by_name);
    if (!rc && count > 1) {
      sylva__id_ref *refs = malloc((size_t)count * sizeof *refs);
      if (!refs) {
        rc = sylva__fail_nomem(p);
      } else {
        for (int k = 0; k < count; k++) refs[k] = (sylva__id_ref){s->plants[k].id, k};
        int first, second;
        if (sylva__find_duplicate(refs, count, &first, &second)) {
          char q[80];
          size_t o2 = sylva__ptr_push_index(p, (size_t)second);
          rc = sylva__fail_at_key(p, "id", "duplicate plant id %s (also %.*s/plants/%d/id)",
                                  sylva__quote(q, s->plants[second].id), (int)p->base, p->ptr,
                                  first);
          sylva__ptr_pop(p, o2);
        }
        free(refs);
      }
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }

  if ((item = member(root, "light")) && (rc = sylva__parse_light(p, item, &s->light))) return rc;
  if ((item = member(root, "site")) && (rc = parse_site(p, item, s))) return rc;

  if ((item = member(root, "obstacles"))) {
    old = sylva__ptr_push(p, "obstacles");
    int count = cJSON_IsArray(item) ? cJSON_GetArraySize(item) : 0;
    if (!cJSON_IsArray(item))
      rc = sylva__fail(p, "expected an array, got %s", sylva__type_name(item));
    else if (count > SYLVA_SCENARIO_MAX_OBSTACLES)
      rc = sylva__fail(p, "%d obstacles; at most %d are allowed", count,
                       SYLVA_SCENARIO_MAX_OBSTACLES);
    if (!rc && count && !(s->obstacles = calloc((size_t)count, sizeof *s->obstacles)))
      rc = sylva__fail_nomem(p);
    int i = 0;
    for (const cJSON *o = rc ? NULL : item->child; o && !rc; o = o->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      rc = sylva__parse_obstacle(p, o, &s->obstacles[i]);
      sylva__ptr_pop(p, o2);
      s->obstacle_count = i + 1;
    }
    if (!rc && count > 1) {
      sylva__id_ref *refs = malloc((size_t)count * sizeof *refs);
      if (!refs) {
        rc = sylva__fail_nomem(p);
      } else {
        for (int k = 0; k < count; k++) refs[k] = (sylva__id_ref){s->obstacles[k].id, k};
        int first, second;
        if (sylva__find_duplicate(refs, count, &first, &second)) {
          char q[80];
          size_t o2 = sylva__ptr_push_index(p, (size_t)second);
          rc = sylva__fail_at_key(p, "id", "duplicate obstacle id %s (also %.*s/obstacles/%d/id)",
                                  sylva__quote(q, s->obstacles[second].id), (int)p->base, p->ptr,
                                  first);
          sylva__ptr_pop(p, o2);
        }
        free(refs);
      }
    }
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  if ((item = member(root, "management")) && (rc = sylva__parse_management(p, item, s)))
    return rc;

  if (!voxel) {
    /* rho / 2 of the smallest rho in use: of the planted species, or of all
     * species when nothing is planted. */
    double rho = HUGE_VAL;
    for (int i = 0; i < s->plant_count; i++)
      rho = fmin(rho, s->species[s->plants[i].species].def.rho);
    if (s->plant_count == 0)
      for (int i = 0; i < s->species_count; i++) rho = fmin(rho, s->species[i].def.rho);
    s->voxel = isinf(rho) ? sylva_default_world_def().voxel : rho / 2;
  }
  return check_world_size(p, s);
}

int sylva__scenario_from_json(sylva__parser *p, const cJSON *root, unsigned flags,
                              sylva_scenario **out) {
  *out = NULL;
  sylva_scenario *s = calloc(1, sizeof *s);
  int rc = s ? parse_top(p, root, flags, s) : sylva__fail_nomem(p);
  if (rc) {
    scenario_free_parts(s);
    return rc;
  }
  *out = s;
  return 0;
}

int sylva_scenario_parse(const char *text, size_t len, sylva_scenario **out, char *err,
                         size_t errlen) {
  return sylva_scenario_parse_ex(text, len, 0, out, err, errlen);
}

int sylva_scenario_parse_ex(const char *text, size_t len, unsigned flags, sylva_scenario **out,
                            char *err, size_t errlen) {
  *out = NULL;
  if (err && errlen) err[0] = '\0';
  char syntax[400];
  if (sylva_json_check_ex(text, len, SYLVA_SCENARIO_MAX_DEPTH,
                          SYLVA_JSON_NO_NUL_ESCAPE | SYLVA_JSON_CJSON_NUMBERS, syntax,
                          sizeof syntax) != 0) {
    if (err && errlen) snprintf(err, errlen, "(syntax) %s", syntax);
    return SYLVA_EINVAL;
  }
  sylva__parser p = {.ptr = "", .plen = 0, .base = 0, .err = err, .errlen = errlen};
  cJSON *root = cJSON_ParseWithLength(text, len);
  if (!root) {
    /* The text is valid JSON, so this is memory, or a limit of cJSON itself. */
    const char *at = cJSON_GetErrorPtr();
    size_t offset = at && at >= text && at <= text + len ? (size_t)(at - text) : len;
    if (err && errlen)
      snprintf(err, errlen, "out of memory while parsing JSON (or cJSON could not read the text near byte %zu)", offset);
    return SYLVA_ENOMEM;
  }
  int rc = sylva__scenario_from_json(&p, root, flags, out);
  cJSON_Delete(root);
  return rc;
}

/* ---- canonical JSON ---- */

static void put_vec3(sylva__strbuf *b, const double v[3]) {
  for (int i = 0; i < 3; i++) {
    sylva__strbuf_puts(b, i ? ", " : "[");
    sylva__strbuf_shortest(b, v[i]);
  }
  sylva__strbuf_putc(b, ']');
}

static void put_species(sylva__strbuf *b, const sylva_species_def *d) {
  sylva__strbuf_puts(b, "{\"rho\": ");
  sylva__strbuf_shortest(b, d->rho);
  sylva__strbuf_printf(b, ", \"growth\": {\"equation\": \"%s\"", sylva_equation_name(d->growth.kind));
  const char *const *names = equation_params[d->growth.kind];
  for (int i = 0; i < 3 && names[i]; i++) {
    sylva__strbuf_printf(b, ", \"%s\": ", names[i]);
    sylva__strbuf_shortest(b, d->growth.p[i]);
  }
  sylva__strbuf_printf(b, "}, \"allocation\": \"%s\"",
                       d->allocation == SYLVA_ALLOC_NONE ? "none" : "lgtm");
  for (size_t i = 0; i < sizeof species_fields / sizeof species_fields[0]; i++) {
    const species_field *f = &species_fields[i];
    if (strcmp(f->key, "rho") == 0) continue;
    const char *at = (const char *)d + f->offset;
    int iv = 0;
    double dv = 0;
    if (f->integer)
      memcpy(&iv, at, sizeof iv);
    else
      memcpy(&dv, at, sizeof dv);
    /* at their defaults, the IGM species keep the canonical bytes they had */
    if (f->scaled && (f->integer ? iv == f->dflt : dv == f->dflt)) continue;
    sylva__strbuf_printf(b, ", \"%s\": ", f->key);
    if (is_colour(f))
      sylva__strbuf_printf(b, "\"#%06x\"", (unsigned)iv);
    else if (f->integer)
      sylva__strbuf_printf(b, "%d", iv);
    else
      sylva__strbuf_shortest(b, dv);
  }
  sylva__strbuf_puts(b, ", \"tropism\": ");
  put_vec3(b, d->tropism);
  sylva__strbuf_printf(b, ", \"markers\": {\"m0\": %d, \"m_min\": %d, \"cone_angle\": ", d->m0,
                       d->m_min);
  sylva__strbuf_shortest(b, d->cone_angle);
  sylva__strbuf_puts(b, ", \"cone_radius\": ");
  sylva__strbuf_shortest(b, d->cone_radius);
  sylva__strbuf_puts(b, "}}");
}

char *sylva_scenario_json(const sylva_scenario *s) {
  sylva__strbuf b = {0};
  sylva__strbuf_puts(&b, "{\n  \"format\": \"" SYLVA_SCENARIO_FORMAT "\",\n  \"name\": ");
  sylva__strbuf_json_string(&b, s->name);
  sylva__strbuf_printf(&b, ",\n  \"seed\": %llu,\n  \"iterations\": %d,",
                       (unsigned long long)s->seed, s->iterations);
  if (s->start_year) /* given only: scenarios without it stay as they were */
    sylva__strbuf_printf(&b, "\n  \"start_year\": %d,", s->start_year);
  if (s->stand_area > 0.0) { /* likewise */
    sylva__strbuf_puts(&b, "\n  \"stand_area\": ");
    sylva__strbuf_shortest(&b, s->stand_area);
    sylva__strbuf_putc(&b, ',');
  }
  sylva__strbuf_puts(&b, "\n  \"world\": {\"min\": ");
  put_vec3(&b, s->world_min);
  sylva__strbuf_puts(&b, ", \"max\": ");
  put_vec3(&b, s->world_max);
  sylva__strbuf_puts(&b, ", \"voxel\": ");
  sylva__strbuf_shortest(&b, s->voxel);
  sylva__strbuf_puts(&b, "},\n  \"species\": {");
  for (int i = 0; i < s->species_count; i++) {
    sylva__strbuf_puts(&b, i ? ",\n    " : "\n    ");
    sylva__strbuf_json_string(&b, s->species[i].name);
    sylva__strbuf_puts(&b, ": ");
    put_species(&b, &s->species[i].def);
  }
  sylva__strbuf_puts(&b, s->species_count ? "\n  },\n  \"plants\": [" : "},\n  \"plants\": [");
  for (int i = 0; i < s->plant_count; i++) {
    const sylva_scenario_plant *pl = &s->plants[i];
    sylva__strbuf_puts(&b, i ? ",\n    {\"id\": " : "\n    {\"id\": ");
    sylva__strbuf_json_string(&b, pl->id);
    sylva__strbuf_puts(&b, ", \"species\": ");
    sylva__strbuf_json_string(&b, s->species[pl->species].name);
    sylva__strbuf_puts(&b, ", \"roots\": [");
    for (int r = 0; r < pl->root_count; r++) {
      if (r) sylva__strbuf_puts(&b, ", ");
      put_vec3(&b, pl->roots[r]);
    }
    sylva__strbuf_puts(&b, "]");
    if (pl->age) sylva__strbuf_printf(&b, ", \"age\": %d", pl->age);
    if (pl->from_file) {
      sylva__strbuf_puts(&b, ", \"from\": {\"file\": ");
      sylva__strbuf_json_string(&b, pl->from_file);
      if (pl->from_format[0]) {
        sylva__strbuf_puts(&b, ", \"format\": ");
        sylva__strbuf_json_string(&b, pl->from_format);
      }
      if (pl->from_model) sylva__strbuf_printf(&b, ", \"model\": %d", pl->from_model);
      if (pl->from_age >= 0) sylva__strbuf_printf(&b, ", \"age\": %d", pl->from_age);
      sylva__strbuf_putc(&b, '}');
    }
    sylva__strbuf_putc(&b, '}');
  }
  sylva__strbuf_puts(&b, s->plant_count ? "\n  ],\n  \"obstacles\": [" : "],\n  \"obstacles\": [");
  for (int i = 0; i < s->obstacle_count; i++) {
    const sylva_scenario_obstacle *o = &s->obstacles[i];
    sylva__strbuf_puts(&b, i ? ",\n    " : "\n    ");
    sylva_obstacle_def od = sylva_scenario_obstacle_def(o);
    sylva__put_obstacle(&b, &od, false);
  }
  sylva__strbuf_puts(&b, s->obstacle_count ? "\n  ]" : "]");
  if (s->management_count) { /* none is the default: such scenarios stay as they were */
    sylva__strbuf_puts(&b, ",\n  \"management\": ");
    sylva__put_management(&b, s);
  }
  if (s->light.site) { /* the zenith sky is the default: its scenarios stay as they were */
    sylva__strbuf_puts(&b, ",\n  \"light\": ");
    sylva__put_light(&b, &s->light);
  }
  if (s->site_crs[0]) {
    sylva__strbuf_puts(&b, ",\n  \"site\": {\"crs\": ");
    sylva__strbuf_json_string(&b, s->site_crs);
    sylva__strbuf_puts(&b, ", \"origin\": [");
    sylva__strbuf_shortest(&b, s->site_origin[0]);
    sylva__strbuf_puts(&b, ", ");
    sylva__strbuf_shortest(&b, s->site_origin[1]);
    sylva__strbuf_puts(&b, "]}");
  }
  sylva__strbuf_puts(&b, "\n}\n");
  return sylva__strbuf_finish(&b);
}

/* ---- building the world ---- */

int sylva_scenario_build(const sylva_scenario *s, sylva_world **out, char *err, size_t errlen) {
  *out = NULL;
  if (err && errlen) err[0] = '\0';
  sylva__parser p = {.ptr = "", .plen = 0, .base = 0, .err = err, .errlen = errlen};
  sylva_world_def def = world_def_of(s, s->voxel);
  sylva_sky_dir *sky = NULL;
  if (s->light.site) { /* the site's sky, as weighted directions (sky.c) */
    if (!(sky = malloc((size_t)s->light.sky.samples * sizeof *sky))) return sylva__fail_nomem(&p);
    sylva_sky_build(&s->light.sky, sky);
    def.sky = sky;
    def.sky_count = s->light.sky.samples;
  }
  sylva_world *w = NULL;
  int rc = sylva_world_create(&def, &w);
  free(sky); /* the world has its own copy */
  if (rc < 0) {
    if (rc == SYLVA_ENOMEM) return sylva__fail_nomem(&p);
    size_t old = sylva__ptr_push(&p, "world");
    rc = fail_status(&p, rc, "%s", sylva_strerror(rc));
    sylva__ptr_pop(&p, old);
    return rc;
  }
  int *species_ids = malloc(((size_t)s->species_count + 1) * sizeof *species_ids);
  if (!species_ids) {
    sylva_world_destroy(w);
    return sylva__fail_nomem(&p);
  }
  for (int i = 0; i < s->species_count; i++) {
    rc = sylva_world_add_species(w, &s->species[i].def, s->species[i].name);
    if (rc < 0) {
      size_t old = sylva__ptr_push(&p, "species");
      sylva__ptr_push(&p, s->species[i].name);
      rc = fail_status(&p, rc, "%s", sylva_strerror(rc));
      sylva__ptr_pop(&p, old);
      goto fail;
    }
    species_ids[i] = rc;
  }
  /* Obstacles first, so that a root inside one is found when its plant is added. */
  for (int i = 0; i < s->obstacle_count; i++) {
    const sylva_scenario_obstacle *o = &s->obstacles[i];
    sylva_obstacle_def od = sylva_scenario_obstacle_def(o);
    rc = sylva_world_add_obstacle(w, &od);
    if (rc < 0) {
      size_t old = sylva__ptr_push(&p, "obstacles");
      sylva__ptr_push_index(&p, (size_t)i);
      rc = fail_status(&p, rc, "%s", sylva_strerror(rc));
      sylva__ptr_pop(&p, old);
      goto fail;
    }
  }
  for (int i = 0; i < s->plant_count; i++) {
    const sylva_scenario_plant *pl = &s->plants[i];
    sylva_plant_def pd = {
        .species = species_ids[pl->species],
        .label = pl->id,
        .roots = (const double(*)[3])pl->roots,
        .root_count = pl->root_count,
        .age = pl->age,
    };
    if (pl->from_file) {
      if (!pl->nodes) {
        size_t old = sylva__ptr_push(&p, "plants");
        sylva__ptr_push_index(&p, (size_t)i);
        sylva__ptr_push(&p, "from");
        rc = fail_status(&p, SYLVA_EINVAL, "the measured tree's file was not read");
        sylva__ptr_pop(&p, old);
        goto fail;
      }
      pd.roots = NULL;
      pd.root_count = 0;
      pd.nodes = pl->nodes;
      pd.node_count = pl->node_count;
      pd.age = pl->measured_age;
    }
    int bad_root = -1;
    rc = sylva_world_add_plant(w, &pd, &bad_root);
    if (rc < 0) {
      size_t old = sylva__ptr_push(&p, "plants");
      sylva__ptr_push_index(&p, (size_t)i);
      if (pl->from_file) {
        sylva__ptr_push(&p, "from");
      } else if (bad_root >= 0 && bad_root < pl->root_count) {
        sylva__ptr_push(&p, "roots");
        sylva__ptr_push_index(&p, (size_t)bad_root);
      }
      if (pl->from_file && bad_root >= 0) {
        const sylva_plant_node *d = &pl->nodes[bad_root];
        rc = fail_status(&p, rc, "the measured tree's node %d at [%g, %g, %g]: %s", bad_root,
                         d->p[0], d->p[1], d->p[2],
                         rc == SYLVA_EBLOCKED ? "inside an obstacle" : sylva_strerror(rc));
      } else if (rc == SYLVA_EBLOCKED) {
        rc = fail_status(&p, rc, "root inside an obstacle");
      } else if (rc == SYLVA_EOUTSIDE) {
        char a[SYLVA_FMT_BUFSIZE * 3], b[SYLVA_FMT_BUFSIZE * 3];
        snprintf(a, sizeof a, "[%g, %g, %g]", s->world_min[0], s->world_min[1], s->world_min[2]);
        snprintf(b, sizeof b, "[%g, %g, %g]", s->world_max[0], s->world_max[1], s->world_max[2]);
        rc = fail_status(&p, rc, "%s (the world spans %s to %s)", sylva_strerror(rc), a, b);
      } else {
        rc = fail_status(&p, rc, "%s", sylva_strerror(rc));
      }
      sylva__ptr_pop(&p, old);
      goto fail;
    }
  }
  rc = sylva__build_management(&p, s, w);
  if (rc) goto fail;
  free(species_ids);
  *out = w;
  return 0;

fail:
  free(species_ids);
  sylva_world_destroy(w);
  return rc;
}

char *sylva_species_json(const sylva_species_def *def) {
  sylva__strbuf b = {0};
  put_species(&b, def);
  return sylva__strbuf_finish(&b);
}

int sylva__species_from_json(const cJSON *obj, sylva_species_def *out) {
  sylva__parser p = {0};
  return parse_species(&p, obj, out);
}
