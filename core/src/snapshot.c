/* Versioned binary image of a world. Layout: 32-byte header (magic "SYLVASNP",
 * u32 version, u32 flags, u64 payload size, u64 FNV-1a 64 of the payload), then
 * the payload, little-endian. Flags: 0, or SKY when the world has a site's sky
 * (its directions follow the seed), so that a world without one has the same
 * bytes as before skies existed; CONFLICTS when the world has zones, pruning
 * schedules, zones entered or nodes pruned since its last step: each obstacle then
 * carries its kind, each stem its pruned count, and the entered zones and the
 * schedules follow the nodes; SCALED when a species has ref_rho, acclimation, years
 * or a nursery: every species record then has those four places too; CROWN with a
 * crown limit, FOLIAGE with foliage not the default, WOOD with heartwood, REACH
 * with a lateral reach, CARBON with a wood density or a biomass allometry (sylva/species_fields.h),
 * PRISMS when an obstacle is a prism: each obstacle then carries its footprint's
 * ring count (0 for a box), ring sizes and points; STAND (which implies CARBON) when a
 * species has a stand's keys, the world a stand_area or a stem a clock of its own or
 * a death: the species records then have places 58 to 64, and after the conflicts
 * come the stand_area and each stem's clock, vigour and death, and a dead stem's
 * measures that its nodes no longer give (docs/model.md, "Stands"). The voxel grid is not stored: shade
 * is an exact integer sum, so re-stamping the live nodes rebuilds it bit for bit. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/snapshot.h"
#include "sylva/species_fields.h"
#include "conflicts.h"
#include "world_impl.h"

static const char magic[8] = {'S', 'Y', 'L', 'V', 'A', 'S', 'N', 'P'};
enum { HEADER = 32 };
/* the header's flags */
enum { SKY = 1, CONFLICTS = 2, SCALED = 4, CROWN = 8, FOLIAGE = 16, WOOD = 32, REACH = 64,
       CARBON = 128, PRISMS = 256, STAND = 512 };
/* Places of the species record that every image has; those up to 42 only with SCALED,
 * 43 and 44 only with CROWN (which implies SCALED), 45 to 47 only with FOLIAGE (which
 * implies both), 48 only with WOOD (which implies all three), 49 only with REACH
 * (which implies all four), the rest only with CARBON (which implies all five). */
enum {
  PLACES_BEFORE_SCALED = 37,
  PLACES_BEFORE_CROWN = 43,
  PLACES_BEFORE_FOLIAGE = 45,
  PLACES_BEFORE_WOOD = 48,
  PLACES_BEFORE_REACH = 49,
  PLACES_BEFORE_CARBON = 50,
  PLACES_BEFORE_STAND = 58
};

static int species_places(uint32_t flags) {
  return (flags & STAND)     ? SYLVA_SPECIES_SNAPSHOT_FIELDS
         : (flags & CARBON)  ? PLACES_BEFORE_STAND
         : (flags & REACH)   ? PLACES_BEFORE_CARBON
         : (flags & WOOD)    ? PLACES_BEFORE_REACH
         : (flags & FOLIAGE) ? PLACES_BEFORE_WOOD
         : (flags & CROWN)   ? PLACES_BEFORE_FOLIAGE
         : (flags & SCALED)  ? PLACES_BEFORE_CROWN
                             : PLACES_BEFORE_SCALED;
}

typedef struct writer {
  uint8_t *buf;
  size_t len, cap;
  bool failed;
} writer;

static void put(writer *o, const void *p, size_t n) {
  if (o->failed) return;
  if (o->len + n > o->cap) {
    size_t cap = o->cap ? o->cap : 4096;
    while (cap < o->len + n) cap *= 2;
    uint8_t *b = sylva__realloc(o->buf, cap);
    if (!b) {
      o->failed = true;
      return;
    }
    o->buf = b;
    o->cap = cap;
  }
  memcpy(o->buf + o->len, p, n);
  o->len += n;
}

static void put_u64(writer *o, uint64_t v) {
  uint8_t b[8];
  for (int i = 0; i < 8; i++) b[i] = (uint8_t)(v >> (8 * i));
  put(o, b, 8);
}
static void put_u32(writer *o, uint32_t v) {
  uint8_t b[4];
  for (int i = 0; i < 4; i++) b[i] = (uint8_t)(v >> (8 * i));
  put(o, b, 4);
}
static void put_i32(writer *o, int32_t v) { put_u32(o, (uint32_t)v); }
static void put_u8(writer *o, uint8_t v) { put(o, &v, 1); }
static void put_f64(writer *o, double v) {
  uint64_t u;
  memcpy(&u, &v, 8);
  put_u64(o, u);
}
static void put_f32(writer *o, float v) {
  uint32_t u;
  memcpy(&u, &v, 4);
  put_u32(o, u);
}
static void put_str(writer *o, const char *s) {
  size_t n = strlen(s);
  put_u32(o, (uint32_t)n);
  put(o, s, n);
}

static uint64_t fnv1a(const uint8_t *p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

/* The species record after growth.kind and allocation: every double of a species,
 * then every int, each at its place in sylva/species_fields.h. */
typedef struct species_slot {
  size_t offset;
  bool is_int;
} species_slot;

#define SYLVA__SLOT_double(name) {offsetof(sylva_species_def, name), false}
#define SYLVA__SLOT_int(name) {offsetof(sylva_species_def, name), true}
#define SYLVA__SLOT(name, type, def, lo, hi, bounds, group, snap) [snap] = SYLVA__SLOT_##type(name),
static const species_slot species_record[SYLVA_SPECIES_SNAPSHOT_FIELDS] = {
    SYLVA_SPECIES_FIELDS(SYLVA__SLOT)
    /* not in the list: the equation's parameters and the tropism vector */
    [1] = SYLVA__SLOT_double(growth.p[0]),
    [2] = SYLVA__SLOT_double(growth.p[1]),
    [3] = SYLVA__SLOT_double(growth.p[2]),
    [14] = SYLVA__SLOT_double(tropism[0]),
    [15] = SYLVA__SLOT_double(tropism[1]),
    [16] = SYLVA__SLOT_double(tropism[2]),
};
#undef SYLVA__SLOT
#undef SYLVA__SLOT_double
#undef SYLVA__SLOT_int
/* Every place is filled once: a place named twice is an error (-Woverride-init), so
 * as many entries as places leave none empty. */
#define SYLVA__COUNT(name, type, def, lo, hi, bounds, group, snap) +1
_Static_assert(0 SYLVA_SPECIES_FIELDS(SYLVA__COUNT) + 6 == SYLVA_SPECIES_SNAPSHOT_FIELDS,
               "a snapshot place of the species record is empty");
#undef SYLVA__COUNT

static void put_species(writer *o, const sylva_species_def *d, int places) {
  for (int i = 0; i < places; i++) {
    const char *at = (const char *)d + species_record[i].offset;
    if (species_record[i].is_int) {
      int v;
      memcpy(&v, at, sizeof v);
      put_i32(o, v);
    } else {
      double v;
      memcpy(&v, at, sizeof v);
      put_f64(o, v);
    }
  }
}

static void put_stats(writer *o, const sylva_stem_stats *s, bool carbon) {
  put_f64(o, s->height);
  put_f64(o, s->dbh);
  put_f64(o, s->crown_width);
  put_f64(o, s->crown_base);
  put_f64(o, s->light);
  put_u64(o, (uint64_t)s->nodes);
  put_u64(o, (uint64_t)s->shed);
  put_i32(o, s->cap);
  if (carbon) put_f64(o, s->co2_sequestered);
}

/* Does the image need the CONFLICTS parts? */
static bool has_conflicts(const sylva_world *w) {
  if (w->reports || w->entered.len || w->prunes.len) return true;
  for (int s = 0; s < w->grid.obstacle_slots; s++)
    if (w->grid.obstacles[s].live && w->grid.obstacles[s].zone) return true;
  for (int k = 0; k < w->stem_count; k++)
    if (w->stems[k].stats.pruned) return true;
  return false;
}

int sylva_snapshot_save(const sylva_world *w, uint8_t **data, size_t *size) {
  *data = NULL;
  *size = 0;
  if (w->status) return w->status;
  writer o = {0};
  bool conflicts = has_conflicts(w);
  bool scaled = false, crown = false, foliage = false, wood = false, reach = false,
       carbon = false, stand = false;
  const sylva_species_def plain = sylva_default_species_def();
  for (int i = 0; i < w->species_count; i++) {
    const sylva_species_def *d = &w->species[i].given;
    stand = stand || d->stock_spread != plain.stock_spread ||
            d->vigour_spread != plain.vigour_spread || d->height_light != plain.height_light ||
            d->mortality_light != plain.mortality_light ||
            d->mortality_years != plain.mortality_years || d->mortality != plain.mortality ||
            d->snag_years != plain.snag_years;
  }
  stand = stand || w->def.stand_area != 0.0;
  for (int k = 0; k < w->stem_count && !stand; k++) {
    const sylva__stem *st = &w->stems[k];
    double local = (double)(w->iteration - st->born);
    stand = st->rate != 1.0 || st->clock != local || st->clock_prev != local - 1.0 ||
            sylva__stem_dead(st) || st->low != 0;
  }
  for (int i = 0; i < w->species_count; i++) {
    const sylva_species_def *d = &w->species[i].given;
    carbon = carbon || stand || d->wood_density != 0.0 || d->biomass_form != 0 ||
             d->biomass_a != 0.0 || d->biomass_b != 0.0 || d->biomass_c != 0.0 ||
             d->biomass_p != 0.0 || d->biomass_q != 0.0 || d->biomass_factor != 1.0;
    reach = reach || carbon || d->lateral_reach != 1.0;
    wood = wood || reach || d->heartwood != 0.0;
    foliage = foliage || wood || d->leaf_size != plain.leaf_size ||
              d->leaf_density != plain.leaf_density || d->leaf_colour != plain.leaf_colour;
    crown = crown || foliage || d->crown_max != 0.0 || d->crown_max_exp != 1.0;
    scaled = scaled || crown || d->ref_rho != 0.0 || d->acclimation != 0.0 || d->years ||
             d->nursery || d->shade_weight != 1.0 || d->lift != 0.0;
  }
  uint32_t flags =
      (w->def.sky_count ? SKY : 0) | (conflicts ? CONFLICTS : 0) | (scaled ? SCALED : 0) |
      (crown ? CROWN : 0) | (foliage ? FOLIAGE : 0) | (wood ? WOOD : 0) | (reach ? REACH : 0) |
      (carbon ? CARBON : 0) | (stand ? STAND : 0);
  bool prisms = false;
  for (int s = 0; s < w->grid.obstacle_slots; s++)
    prisms = prisms || (w->grid.obstacles[s].live && w->grid.obstacles[s].fp);
  if (prisms) flags |= PRISMS;
  int places = species_places(flags);
  uint8_t zero[HEADER] = {0};
  put(&o, zero, HEADER);
  for (int a = 0; a < 3; a++) put_f64(&o, w->def.min[a]);
  for (int a = 0; a < 3; a++) put_f64(&o, w->def.max[a]);
  put_f64(&o, w->def.voxel);
  put_u64(&o, w->def.seed);
  if (w->def.sky_count) {
    put_u32(&o, (uint32_t)w->def.sky_count);
    for (int i = 0; i < w->def.sky_count; i++) {
      for (int a = 0; a < 3; a++) put_f64(&o, w->def.sky[i].d[a]);
      put_f64(&o, w->def.sky[i].weight);
    }
  }
  put_i32(&o, w->iteration);
  for (int i = 0; i < 4; i++) put_u64(&o, w->rng.s[i]);
  put_i32(&o, w->nodes.next_id);
  put_u32(&o, (uint32_t)w->species_count);
  for (int i = 0; i < w->species_count; i++) {
    const sylva_species_def *d = &w->species[i].given;
    put_str(&o, w->species[i].label);
    put_u32(&o, (uint32_t)d->growth.kind);
    put_u32(&o, (uint32_t)d->allocation);
    put_species(&o, d, places);
  }
  put_i32(&o, w->grid.next_obstacle_id);
  put_u32(&o, (uint32_t)w->grid.obstacle_count);
  for (int s = 0; s < w->grid.obstacle_slots; s++) { /* the live ones, in order */
    const sylva__obstacle *ob = &w->grid.obstacles[s];
    if (!ob->live) continue;
    put_i32(&o, ob->id);
    put_str(&o, ob->label);
    for (int a = 0; a < 3; a++) put_f64(&o, ob->min[a]);
    for (int a = 0; a < 3; a++) put_f64(&o, ob->max[a]);
    if (conflicts) put_u8(&o, ob->zone);
    if (prisms) {
      const sylva__footprint *f = ob->fp;
      put_u32(&o, f ? (uint32_t)f->ring_count : 0);
      for (int r = 0; f && r < f->ring_count; r++) put_u32(&o, (uint32_t)f->ring_size[r]);
      for (int i = 0; f && i < f->point_count; i++) {
        put_f64(&o, f->pt[i][0]);
        put_f64(&o, f->pt[i][1]);
      }
    }
  }
  put_u32(&o, (uint32_t)w->plant_count);
  for (int i = 0; i < w->plant_count; i++) {
    put_str(&o, w->plants[i].label);
    put_i32(&o, w->plants[i].species);
    put_i32(&o, w->plants[i].stem_count);
  }
  for (int i = 0; i < w->stem_count; i++) {
    const sylva__stem *st = &w->stems[i];
    put_i32(&o, st->born);
    for (int a = 0; a < 3; a++) put_f64(&o, st->root[a]);
    put_u8(&o, st->finished);
    put_stats(&o, &st->stats, carbon);
    if (conflicts) put_u64(&o, (uint64_t)st->stats.pruned);
  }
  /* live nodes, links as indices among live nodes */
  const sylva__skeleton *s = &w->nodes;
  int32_t *index = sylva__malloc((s->count + 1) * sizeof *index);
  if (!index) {
    sylva__free(o.buf);
    return SYLVA_ENOMEM;
  }
  int32_t live = 0;
  for (size_t i = 0; i < s->count; i++) index[i] = (s->flags[i] & SYLVA__NODE_ALIVE) ? live++ : -1;
  put_u32(&o, (uint32_t)live);
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    put_i32(&o, s->id[i]);
    put_i32(&o, s->parent[i] >= 0 ? index[s->parent[i]] : -1);
    put_i32(&o, s->axis_child[i] >= 0 ? index[s->axis_child[i]] : -1);
    put_i32(&o, s->lateral_child[i] >= 0 ? index[s->lateral_child[i]] : -1);
    put_f32(&o, s->x[i]);
    put_f32(&o, s->y[i]);
    put_f32(&o, s->z[i]);
    put_f32(&o, s->radius[i]);
    put_i32(&o, s->birth[i]);
    put_i32(&o, s->stem[i]);
    put_i32(&o, s->depth[i]);
    put_u8(&o, s->flags[i]);
  }
  sylva__free(index);
  if (conflicts) {
    put_u32(&o, (uint32_t)w->entered.len);
    for (size_t i = 0; i < w->entered.len; i++) {
      put_i32(&o, w->entered.data[i].stem);
      put_i32(&o, w->entered.data[i].zone);
      put_i32(&o, w->entered.data[i].first);
    }
    put_u32(&o, (uint32_t)w->prunes.len);
    for (size_t i = 0; i < w->prunes.len; i++) {
      put_i32(&o, w->prunes.data[i].zone);
      put_i32(&o, w->prunes.data[i].every);
      put_i32(&o, w->prunes.data[i].from);
    }
  }
  if (stand) {
    put_f64(&o, w->def.stand_area);
    for (int k = 0; k < w->stem_count; k++) {
      const sylva__stem *st = &w->stems[k];
      const sylva_stem_stats *m = &st->stats;
      put_f64(&o, st->clock);
      put_f64(&o, st->clock_prev);
      put_f64(&o, st->rate);
      put_i32(&o, st->low);
      put_f64(&o, m->vigour);
      put_i32(&o, m->died);
      put_i32(&o, m->fallen);
      if (!sylva__stem_dead(st)) continue;
      /* what its nodes no longer give: the measures of its last season alive */
      const double kept[] = {m->leaf_area, m->crown_area, m->wood_volume, m->biomass,
                             m->biomass_model, m->carbon, m->co2};
      for (size_t i = 0; i < sizeof kept / sizeof *kept; i++) put_f64(&o, kept[i]);
    }
  }
  if (o.failed) {
    sylva__free(o.buf);
    return SYLVA_ENOMEM;
  }
  uint64_t payload = o.len - HEADER;
  memcpy(o.buf, magic, 8);
  uint8_t *h = o.buf + 8;
  uint32_t version = SYLVA_SNAPSHOT_VERSION;
  for (int i = 0; i < 4; i++) h[i] = (uint8_t)(version >> (8 * i));
  for (int i = 0; i < 4; i++) h[4 + i] = (uint8_t)(flags >> (8 * i));
  for (int i = 0; i < 8; i++) h[8 + i] = (uint8_t)(payload >> (8 * i));
  uint64_t sum = fnv1a(o.buf + HEADER, payload);
  for (int i = 0; i < 8; i++) h[16 + i] = (uint8_t)(sum >> (8 * i));
  *data = o.buf;
  *size = o.len;
  return SYLVA_OK;
}

/* ---- reading ----------------------------------------------------------------- */

typedef struct reader {
  const uint8_t *p;
  size_t len, pos;
  bool bad;
} reader;

static const uint8_t *take(reader *r, size_t n) {
  if (r->bad || r->len - r->pos < n) {
    r->bad = true;
    return NULL;
  }
  const uint8_t *p = r->p + r->pos;
  r->pos += n;
  return p;
}
static uint64_t get_u64(reader *r) {
  const uint8_t *b = take(r, 8);
  uint64_t v = 0;
  if (b)
    for (int i = 0; i < 8; i++) v |= (uint64_t)b[i] << (8 * i);
  return v;
}
static uint32_t get_u32(reader *r) {
  const uint8_t *b = take(r, 4);
  uint32_t v = 0;
  if (b)
    for (int i = 0; i < 4; i++) v |= (uint32_t)b[i] << (8 * i);
  return v;
}
static int32_t get_i32(reader *r) { return (int32_t)get_u32(r); }
static uint8_t get_u8(reader *r) {
  const uint8_t *b = take(r, 1);
  return b ? *b : 0;
}
static double get_f64(reader *r) {
  uint64_t u = get_u64(r);
  double v;
  memcpy(&v, &u, 8);
  return v;
}
static float get_f32(reader *r) {
  uint32_t u = get_u32(r);
  float v;
  memcpy(&v, &u, 4);
  return v;
}
/* A label: 1..SYLVA_LABEL_MAX-1 bytes without NUL. */
static bool get_label(reader *r, char out[SYLVA_LABEL_MAX]) {
  uint32_t n = get_u32(r);
  if (r->bad || n == 0 || n >= SYLVA_LABEL_MAX) return r->bad = true, false;
  const uint8_t *b = take(r, n);
  if (!b || memchr(b, 0, n)) return r->bad = true, false;
  memcpy(out, b, n);
  out[n] = 0;
  return true;
}

static void get_stats(reader *r, sylva_stem_stats *s, bool carbon) {
  s->height = get_f64(r);
  s->dbh = get_f64(r);
  s->crown_width = get_f64(r);
  s->crown_base = get_f64(r);
  s->light = get_f64(r);
  s->nodes = (int64_t)get_u64(r);
  s->shed = (int64_t)get_u64(r);
  s->cap = get_i32(r);
  s->co2_sequestered = carbon ? get_f64(r) : NAN;
}

static void get_species(reader *r, sylva_species_def *d, int places) {
  for (int i = 0; i < places; i++) {
    char *at = (char *)d + species_record[i].offset;
    if (species_record[i].is_int) {
      int v = get_i32(r);
      memcpy(at, &v, sizeof v);
    } else {
      double v = get_f64(r);
      memcpy(at, &v, sizeof v);
    }
  }
}

#define SYLVA__FAIL(code) \
  do {                    \
    rc = (code);          \
    goto fail;            \
  } while (0)

static int read_world(reader *r, uint32_t flags, sylva_world **out) {
  bool has_sky = flags & SKY, conflicts = flags & CONFLICTS;
  int rc = SYLVA_OK;
  sylva_world *w = NULL;
  sylva_world_def def = sylva_default_world_def();
  for (int a = 0; a < 3; a++) def.min[a] = get_f64(r);
  for (int a = 0; a < 3; a++) def.max[a] = get_f64(r);
  def.voxel = get_f64(r);
  def.seed = get_u64(r);
  sylva_sky_dir *sky = NULL;
  if (has_sky) {
    uint32_t n = get_u32(r);
    if (r->bad) return SYLVA_ETRUNCATED;
    if (n < 1 || n > SYLVA_MAX_SKY) return SYLVA_EBADIMAGE;
    sky = sylva__calloc(n, sizeof *sky);
    if (!sky) return SYLVA_ENOMEM;
    for (uint32_t i = 0; i < n; i++) {
      for (int a = 0; a < 3; a++) sky[i].d[a] = get_f64(r);
      sky[i].weight = get_f64(r);
    }
    def.sky = sky;
    def.sky_count = (int)n;
  }
  if (r->bad) {
    sylva__free(sky);
    return SYLVA_ETRUNCATED;
  }
  rc = sylva_world_create(&def, &w);
  sylva__free(sky); /* the world has its own copy */
  if (rc) return rc == SYLVA_ENOMEM ? rc : SYLVA_EBADIMAGE;
  int32_t iteration = get_i32(r);
  for (int i = 0; i < 4; i++) w->rng.s[i] = get_u64(r);
  int32_t next_id = get_i32(r);
  if (iteration < 0 || next_id < 0) SYLVA__FAIL(SYLVA_EBADIMAGE);
  w->iteration = iteration;
  uint32_t nspecies = get_u32(r);
  if (nspecies > 100000) SYLVA__FAIL(SYLVA_EBADIMAGE);
  for (uint32_t i = 0; i < nspecies && !r->bad; i++) {
    char label[SYLVA_LABEL_MAX];
    if (!get_label(r, label)) break;
    sylva_species_def d = sylva_default_species_def();
    d.growth.kind = (sylva_equation_kind)get_u32(r);
    d.allocation = (sylva_allocation)get_u32(r);
    get_species(r, &d, species_places(flags));
    if (r->bad) break;
    int id = sylva_world_add_species(w, &d, label);
    if (id < 0) SYLVA__FAIL(id == SYLVA_ENOMEM ? id : SYLVA_EBADIMAGE);
  }
  int32_t next_obstacle = get_i32(r);
  uint32_t nobst = get_u32(r);
  if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
  if (nobst > 1000000 || next_obstacle < 0) SYLVA__FAIL(SYLVA_EBADIMAGE);
  for (uint32_t i = 0; i < nobst && !r->bad; i++) {
    int32_t id = get_i32(r);
    char label[SYLVA_LABEL_MAX];
    if (!get_label(r, label)) break;
    double mn[3], mx[3];
    for (int a = 0; a < 3; a++) mn[a] = get_f64(r);
    for (int a = 0; a < 3; a++) mx[a] = get_f64(r);
    uint8_t zone = conflicts ? get_u8(r) : 0;
    sylva_obstacle_def od = {.label = label, .kind = zone ? SYLVA_OBSTACLE_ZONE : SYLVA_OBSTACLE_SOLID};
    memcpy(od.min, mn, sizeof od.min);
    memcpy(od.max, mx, sizeof od.max);
    int *sizes = NULL;
    double(*pts)[2] = NULL;
    uint32_t rings = (flags & PRISMS) ? get_u32(r) : 0, npts = 0;
    if (r->bad) break;
    if (rings > SYLVA_FOOTPRINT_MAX_POINTS / 3) SYLVA__FAIL(SYLVA_EBADIMAGE);
    if (rings) {
      if (!(sizes = sylva__malloc(rings * sizeof *sizes))) SYLVA__FAIL(SYLVA_ENOMEM);
      for (uint32_t k = 0; k < rings; k++) {
        uint32_t n = get_u32(r);
        if (n > SYLVA_FOOTPRINT_MAX_POINTS - npts) r->bad = true;
        if (r->bad) break;
        sizes[k] = (int)n;
        npts += n;
      }
      if (!r->bad && !(pts = sylva__malloc((npts ? npts : 1) * sizeof *pts))) {
        sylva__free(sizes);
        SYLVA__FAIL(SYLVA_ENOMEM);
      }
      for (uint32_t k = 0; k < npts && !r->bad; k++) {
        pts[k][0] = get_f64(r);
        pts[k][1] = get_f64(r);
      }
      od.footprint = (sylva_footprint){(const double(*)[2])pts, (int)npts, sizes, (int)rings};
    }
    int added = r->bad ? SYLVA_EBADIMAGE : id < 0 || id >= next_obstacle || zone > 1 ? SYLVA_EBADIMAGE
                /* refuses an id at or below the previous one (SYLVA_EINVAL) */
                : sylva__grid_add_obstacle_def(&w->grid, id, &od);
    sylva__free(sizes);
    sylva__free(pts);
    if (r->bad) break;
    if (added < 0) SYLVA__FAIL(added == SYLVA_ENOMEM ? added : SYLVA_EBADIMAGE);
  }
  w->grid.next_obstacle_id = next_obstacle;
  uint32_t nplants = get_u32(r);
  if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
  if (nplants > SYLVA_MAX_STEMS) SYLVA__FAIL(SYLVA_EBADIMAGE);
  w->plants = sylva__calloc(nplants + 1, sizeof *w->plants);
  if (!w->plants) SYLVA__FAIL(SYLVA_ENOMEM);
  w->plant_cap = (int)nplants + 1;
  int64_t nstems = 0;
  for (uint32_t i = 0; i < nplants && !r->bad; i++) {
    sylva__plant *p = &w->plants[i];
    if (!get_label(r, p->label)) break;
    p->species = get_i32(r);
    p->stem_count = get_i32(r);
    p->first_stem = (int)nstems;
    if (p->species < 0 || p->species >= w->species_count || p->stem_count < 1 ||
        nstems + p->stem_count > SYLVA_MAX_STEMS)
      SYLVA__FAIL(SYLVA_EBADIMAGE);
    if (sylva__find_plant(w, p->label) >= 0) SYLVA__FAIL(SYLVA_EBADIMAGE);
    if (sylva__index_plant(w, (int)i)) SYLVA__FAIL(SYLVA_ENOMEM);
    nstems += p->stem_count;
    w->plant_count++;
  }
  if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
  w->stems = sylva__calloc((size_t)nstems + 1, sizeof *w->stems);
  if (!w->stems) SYLVA__FAIL(SYLVA_ENOMEM);
  w->stem_cap = (int)nstems + 1;
  for (int i = 0; i < w->plant_count; i++)
    for (int k = 0; k < w->plants[i].stem_count; k++) {
      sylva__stem *st = &w->stems[w->stem_count++];
      st->plant = i;
      st->index = k;
      st->species = w->plants[i].species;
      st->born = get_i32(r);
      for (int a = 0; a < 3; a++) st->root[a] = get_f64(r);
      uint8_t fin = get_u8(r);
      st->finished = fin != 0;
      get_stats(r, &st->stats, flags & CARBON);
      st->stats.pruned = conflicts ? (int64_t)get_u64(r) : 0;
      st->stats.plant = i;
      st->stats.stem = k;
      st->stats.finished = st->finished;
      /* the measures that follow from the stored ones (stats.c) */
      const sylva_species_def *sd = &w->species[st->species].def;
      st->stats.crown_height = st->stats.height - st->stats.crown_base;
      st->stats.age = sd->years ? (int32_t)(iteration - st->born - sd->nursery) : -1;
      st->root_slot = -1;
      /* a stem grown in the nursery was planted before the world's first iteration */
      int nursery = w->species[st->species].def.years ? -(SYLVA_MAX_AGE + 200) : 0;
      if (fin > 1 || st->born < nursery || st->born > iteration || st->stats.pruned < 0)
        SYLVA__FAIL(SYLVA_EBADIMAGE);
    }
  uint32_t live = get_u32(r);
  if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
  /* every node takes 45 bytes: refuse counts the image cannot hold */
  if ((uint64_t)live * 45 > r->len - r->pos || live > (uint32_t)INT32_MAX)
    SYLVA__FAIL(SYLVA_ETRUNCATED);
  sylva__skeleton *s = &w->nodes;
  if (sylva__skeleton_reserve(s, live)) SYLVA__FAIL(SYLVA_ENOMEM);
  int32_t prev_id = -1;
  for (uint32_t i = 0; i < live; i++) {
    int32_t id = get_i32(r), parent = get_i32(r), axis = get_i32(r), lat = get_i32(r);
    float x = get_f32(r), y = get_f32(r), z = get_f32(r), radius = get_f32(r);
    int32_t birth = get_i32(r), stem = get_i32(r), depth = get_i32(r);
    uint8_t flags = get_u8(r);
    if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
    int v[3];
    if (id <= prev_id || id >= next_id || parent >= (int32_t)i || parent < -1 ||
        axis < -1 || axis >= (int32_t)live || (axis >= 0 && axis <= (int32_t)i) ||
        lat < -1 || lat >= (int32_t)live || (lat >= 0 && lat <= (int32_t)i) || stem < 0 ||
        stem >= w->stem_count || birth < w->stems[stem].born || birth > iteration ||
        depth < 0 || !(flags & SYLVA__NODE_ALIVE) ||
        (flags & ~SYLVA__NODE_STATE) ||
        !(radius > 0.0f) || !isfinite(radius) ||
        !sylva__grid_voxel(&w->grid, x, y, z, v))
      SYLVA__FAIL(SYLVA_EBADIMAGE);
    prev_id = id;
    int32_t slot = sylva__skeleton_append(s, id, parent, x, y, z, radius, birth, stem, depth, flags);
    s->axis_child[slot] = axis;
    s->lateral_child[slot] = lat;
    if (parent < 0) {
      /* one root per stem, at depth 0, on no axis of another node */
      if (w->stems[stem].root_slot >= 0 || depth != 0 || (flags & SYLVA__NODE_LATERAL))
        SYLVA__FAIL(SYLVA_EBADIMAGE);
      w->stems[stem].root_slot = slot;
    } else {
      /* a child must be named by its parent, with the matching kind of link */
      bool lateral = (flags & SYLVA__NODE_LATERAL) != 0;
      int32_t link = lateral ? s->lateral_child[parent] : s->axis_child[parent];
      if (link != slot || s->stem[parent] != stem || depth != s->depth[parent] + 1)
        SYLVA__FAIL(SYLVA_EBADIMAGE);
    }
  }
  if (conflicts) {
    uint32_t n = get_u32(r);
    if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
    if ((uint64_t)n * 12 > r->len - r->pos) SYLVA__FAIL(SYLVA_ETRUNCATED);
    for (uint32_t i = 0; i < n; i++) {
      int32_t stem = get_i32(r), zone = get_i32(r), first = get_i32(r);
      int slot = sylva__grid_obstacle_slot(&w->grid, zone);
      if (stem < 0 || stem >= w->stem_count || zone < 0 || zone >= next_obstacle || first < 0 ||
          first > iteration || (slot >= 0 && !w->grid.obstacles[slot].zone))
        SYLVA__FAIL(SYLVA_EBADIMAGE);
      int erc = sylva__entered_add(w, stem, zone, first);
      if (erc) SYLVA__FAIL(erc == SYLVA_ENOMEM ? erc : SYLVA_EBADIMAGE);
    }
    n = get_u32(r);
    if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
    if ((uint64_t)n * 12 > r->len - r->pos) SYLVA__FAIL(SYLVA_ETRUNCATED);
    for (uint32_t i = 0; i < n; i++) {
      sylva_prune_def d;
      d.zone = get_i32(r);
      d.every = get_i32(r);
      d.from = get_i32(r);
      /* its zone may have been removed since: the schedule then prunes nothing */
      if (d.zone < 0 || d.zone >= next_obstacle || d.every < 0 || d.from < 1)
        SYLVA__FAIL(SYLVA_EBADIMAGE);
      if (SYLVA__VEC_RESERVE(w->prunes, w->prunes.len + 1)) SYLVA__FAIL(SYLVA_ENOMEM);
      w->prunes.data[w->prunes.len++] = d;
    }
    w->reports = true;
  }
  for (int k = 0; k < w->stem_count; k++) { /* as every stem stood before stands */
    sylva__stem *st = &w->stems[k];
    st->clock = (double)(iteration - st->born);
    st->clock_prev = st->clock - 1.0;
    st->rate = 1.0;
    st->stats.alive = true;
    st->stats.died = st->stats.fallen = -1;
    st->stats.vigour = NAN;
  }
  if (flags & STAND) {
    w->def.stand_area = get_f64(r);
    if (!(w->def.stand_area >= 0.0) || !isfinite(w->def.stand_area)) r->bad = true;
    for (int k = 0; k < w->stem_count && !r->bad; k++) {
      sylva__stem *st = &w->stems[k];
      sylva_stem_stats *m = &st->stats;
      st->clock = get_f64(r);
      st->clock_prev = get_f64(r);
      st->rate = get_f64(r);
      st->low = get_i32(r);
      m->vigour = get_f64(r);
      m->died = get_i32(r);
      m->fallen = get_i32(r);
      m->alive = m->died < 0;
      if (r->bad) break;
      if (!isfinite(st->clock) || !isfinite(st->clock_prev) || !(st->clock >= st->clock_prev) ||
          !(st->rate > 0.0) || !isfinite(st->rate) || st->low < 0 || m->died < -1 ||
          m->died > iteration || m->fallen < -1 || m->fallen > iteration ||
          (m->fallen >= 0 && m->fallen < m->died) || (m->died < 0 && m->fallen >= 0))
        SYLVA__FAIL(SYLVA_EBADIMAGE);
      if (m->died < 0) continue;
      /* its measures are its last season's alive, the one before it died */
      const sylva_species_def *sd = &w->species[st->species].def;
      m->age = sd->years ? (int32_t)(m->died - 1 - st->born - sd->nursery) : -1;
      double *kept[] = {&m->leaf_area, &m->crown_area, &m->wood_volume, &m->biomass,
                        &m->biomass_model, &m->carbon, &m->co2};
      for (size_t i = 0; i < sizeof kept / sizeof *kept; i++) *kept[i] = get_f64(r);
    }
    if (r->bad) SYLVA__FAIL(SYLVA_ETRUNCATED);
  }
  if (r->pos != r->len) SYLVA__FAIL(SYLVA_EBADIMAGE);
  s->next_id = next_id;
  /* links that point forward must be answered by the child's parent */
  for (size_t i = 0; i < s->count; i++) {
    if (s->axis_child[i] >= 0 && (s->parent[s->axis_child[i]] != (int32_t)i ||
                                  (s->flags[s->axis_child[i]] & SYLVA__NODE_LATERAL)))
      SYLVA__FAIL(SYLVA_EBADIMAGE);
    if (s->lateral_child[i] >= 0 && (s->parent[s->lateral_child[i]] != (int32_t)i ||
                                     !(s->flags[s->lateral_child[i]] & SYLVA__NODE_LATERAL)))
      SYLVA__FAIL(SYLVA_EBADIMAGE);
  }
  for (int k = 0; k < w->stem_count; k++) /* a root until its snag fell, nodes bare once dead */
    if ((w->stems[k].root_slot < 0) != (w->stems[k].stats.fallen >= 0)) SYLVA__FAIL(SYLVA_EBADIMAGE);
  for (size_t i = 0; i < s->count; i++)
    if (((s->flags[i] & SYLVA__NODE_BARE) != 0) != sylva__stem_dead(&w->stems[s->stem[i]]))
      SYLVA__FAIL(SYLVA_EBADIMAGE);
  /* rebuild occupancy and shade from the live nodes */
  for (size_t i = 0; i < s->count; i++) {
    int v[3];
    sylva__node_voxel(w, (int32_t)i, v);
    if (sylva__grid_blocked(&w->grid, v) && s->birth[i] == w->stems[s->stem[i]].born) {
      /* an initial trunk can never be inside an obstacle */
      SYLVA__FAIL(SYLVA_EBADIMAGE);
    }
    int orc = sylva__grid_occupy(&w->grid, v, s->stem[i]);
    if (orc == SYLVA_ENOMEM) SYLVA__FAIL(SYLVA_ENOMEM);
    if (orc) SYLVA__FAIL(SYLVA_EBADIMAGE);
    orc = sylva__shade_node(w, (int32_t)i, +1);
    if (orc) SYLVA__FAIL(orc);
  }
  rc = sylva__conflicts_update(w, 0); /* the zone lines and clearances, as saved */
  if (rc) SYLVA__FAIL(rc);
  /* the canopy's scratch: slots and stems */
  if (sylva__reserve_scratch(w) ||
      SYLVA__VEC_RESERVE(w->stem_top, sylva__canopy_room(w->stem_count)))
    SYLVA__FAIL(SYLVA_ENOMEM);
  SYLVA__CHECK_WORLD(w, SYLVA__BETWEEN_STEPS);
  sylva__stats_leaf_area(w);
  sylva__stats_loaded(w);
  *out = w;
  return SYLVA_OK;
fail:
  sylva_world_destroy(w);
  return rc;
}

int sylva_snapshot_load(const uint8_t *data, size_t size, sylva_world **out) {
  *out = NULL;
  if (!data || size < HEADER) return SYLVA_ETRUNCATED;
  if (memcmp(data, magic, 8) != 0) return SYLVA_EBADIMAGE;
  uint32_t version = 0, reserved = 0;
  uint64_t payload = 0, sum = 0;
  for (int i = 0; i < 4; i++) version |= (uint32_t)data[8 + i] << (8 * i);
  for (int i = 0; i < 4; i++) reserved |= (uint32_t)data[12 + i] << (8 * i);
  for (int i = 0; i < 8; i++) payload |= (uint64_t)data[16 + i] << (8 * i);
  for (int i = 0; i < 8; i++) sum |= (uint64_t)data[24 + i] << (8 * i);
  if (version != SYLVA_SNAPSHOT_VERSION) return SYLVA_EVERSION;
  if (reserved & ~(uint32_t)(SKY | CONFLICTS | SCALED | CROWN | FOLIAGE | WOOD | REACH | CARBON |
                             PRISMS | STAND))
    return SYLVA_EBADIMAGE;
  if ((reserved & STAND) && !(reserved & CARBON)) return SYLVA_EBADIMAGE;
  if ((reserved & CROWN) && !(reserved & SCALED)) return SYLVA_EBADIMAGE;
  if ((reserved & FOLIAGE) && !(reserved & CROWN)) return SYLVA_EBADIMAGE;
  if ((reserved & WOOD) && !(reserved & FOLIAGE)) return SYLVA_EBADIMAGE;
  if ((reserved & REACH) && !(reserved & WOOD)) return SYLVA_EBADIMAGE;
  if ((reserved & CARBON) && !(reserved & REACH)) return SYLVA_EBADIMAGE;
  if (payload != size - HEADER) return SYLVA_ETRUNCATED;
  if (fnv1a(data + HEADER, payload) != sum) return SYLVA_ECHECKSUM;
  reader r = {data + HEADER, payload, 0, false};
  return read_world(&r, reserved, out);
}
