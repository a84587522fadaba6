/* Deterministic encoders: stats lines, the done line and the skeleton. */
#include "sylva/encode.h"

#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "encode_parts.h"
#include "strbuf.h"

int sylva_fmt_fixed(char *buf, size_t n, double v, int decimals) {
  char tmp[SYLVA_FMT_BUFSIZE];
  if (!isfinite(v)) {
    strcpy(tmp, "null");
  } else {
    if (decimals < 0) decimals = 0;
    if (decimals > 17) decimals = 17;
    snprintf(tmp, sizeof tmp, "%.*f", decimals, v);
    if (strchr(tmp, '.')) {
      size_t len = strlen(tmp);
      while (tmp[len - 1] == '0') tmp[--len] = '\0';
      if (tmp[len - 1] == '.') tmp[--len] = '\0';
    }
    if (strcmp(tmp, "-0") == 0) strcpy(tmp, "0");
  }
  return snprintf(buf, n, "%s", tmp);
}

int sylva_fmt_shortest(char *buf, size_t n, double v) {
  char tmp[SYLVA_FMT_BUFSIZE];
  if (!isfinite(v)) {
    strcpy(tmp, "null");
  } else if (v == 0.0) {
    strcpy(tmp, "0");
  } else {
    int precision = 1;
    for (; precision < 17; precision++) {
      snprintf(tmp, sizeof tmp, "%.*e", precision - 1, v);
      if (strtod(tmp, NULL) == v) break;
    }
    snprintf(tmp, sizeof tmp, "%.*e", precision - 1, v);
    /* Plain decimals for everyday magnitudes ("100", not "1e+02"); the digits
     * are the same, only the notation changes. */
    int exponent = atoi(strchr(tmp, 'e') + 1);
    if (exponent >= -5 && exponent < 17) {
      int decimals = precision - 1 - exponent;
      snprintf(tmp, sizeof tmp, "%.*f", decimals > 0 ? decimals : 0, v);
    } else {
      snprintf(tmp, sizeof tmp, "%.*g", precision, v);
    }
  }
  return snprintf(buf, n, "%s", tmp);
}

/* `"key": ` after a separator (none before the first key). */
static void put_key(sylva__strbuf *b, bool first, const char *key, bool compact) {
  if (!first) sylva__strbuf_puts(b, compact ? "," : ", ");
  sylva__strbuf_putc(b, '"');
  sylva__strbuf_puts(b, key);
  sylva__strbuf_puts(b, compact ? "\":" : "\": ");
}

/* The label of the obstacle with this id ("" for none). */
static const char *obstacle_label(const sylva_world *w, int id) {
  sylva_obstacle_def o;
  return sylva_world_obstacle(w, id, &o) == 0 ? o.label : "";
}

/* `{"road": {"nodes": 3, "first": 7}, ...}`: the zones one stem entered, "first" in
 * calendar years when the run has a start year. */
static void put_zones(sylva__strbuf *b, const sylva_world *w, const sylva_conflicts *c,
                      int start_year, bool compact) {
  sylva__strbuf_putc(b, '{');
  for (size_t i = 0; i < c->zone_count; i++) {
    if (i) sylva__strbuf_puts(b, compact ? "," : ", ");
    sylva__strbuf_json_string(b, obstacle_label(w, c->zones[i].obstacle));
    sylva__strbuf_printf(b, compact ? ":{\"nodes\":%" PRId64 ",\"first\":%" PRId32 "}"
                                    : ": {\"nodes\": %" PRId64 ", \"first\": %" PRId32 "}",
                         c->zones[i].nodes, start_year + c->zones[i].first);
  }
  sylva__strbuf_putc(b, '}');
}

/* `{"wall": 1.25, ...}`: one stem's clearances, metres with 4 decimals. */
static void put_clearance(sylva__strbuf *b, const sylva_world *w, const sylva_conflicts *c,
                          bool compact) {
  sylva__strbuf_putc(b, '{');
  for (size_t i = 0; i < c->clearance_count; i++) {
    if (i) sylva__strbuf_puts(b, compact ? "," : ", ");
    sylva__strbuf_json_string(b, obstacle_label(w, c->clearances[i].obstacle));
    sylva__strbuf_puts(b, compact ? ":" : ": ");
    sylva__strbuf_fixed(b, c->clearances[i].distance, 4);
  }
  sylva__strbuf_putc(b, '}');
}

char *sylva_encode_stem_conflicts(const sylva_world *w, int stem, bool clearance, int start_year) {
  sylva__strbuf b = {0};
  sylva_conflicts c = sylva_world_stem_conflicts(w, stem);
  if (clearance)
    put_clearance(&b, w, &c, true);
  else
    put_zones(&b, w, &c, start_year, true);
  return sylva__strbuf_finish(&b);
}

bool sylva_encode_years(const sylva_world *w) {
  for (int i = 0; i < sylva_world_species_count(w); i++)
    if (sylva_world_species(w, i)->years) return true;
  return false;
}

bool sylva_encode_stand(const sylva_world *w) {
  for (int i = 0; i < sylva_world_species_count(w); i++) {
    const sylva_species_def *d = sylva_world_species(w, i);
    if (d->years || d->mortality > 0.0 || d->mortality_light > 0.0) return true;
  }
  return false;
}

sylva__stats_form sylva__stats_form_of(const sylva_world *w, int start_year) {
  return (sylva__stats_form){sylva_world_reports_conflicts(w), sylva_encode_years(w), start_year,
                             sylva_encode_stand(w)};
}

void sylva_stand_figures(const sylva_stand_stats *s, sylva_stand_figure out[SYLVA_STAND_FIGURES]) {
  const sylva_stand_figure f[SYLVA_STAND_FIGURES] = {
      {"stems_per_ha", s->stems_per_ha, 1}, {"basal_area", s->basal_area, 3},
      {"qmd", s->qmd, 2},                   {"dominant_height", s->dominant_height, 3},
      {"sdi", s->sdi, 1},                   {"cv_height", s->cv_height, 4},
      {"cv_dbh", s->cv_dbh, 4}};
  memcpy(out, f, sizeof f);
}

void sylva__put_stand(sylva__strbuf *b, const sylva_stand_stats *s, bool compact) {
  sylva__strbuf_putc(b, '{');
  put_key(b, true, "area", compact);
  sylva__strbuf_fixed(b, s->area, 1);
  put_key(b, false, "alive", compact);
  sylva__strbuf_printf(b, "%" PRId32, s->alive);
  put_key(b, false, "died", compact);
  sylva__strbuf_printf(b, "%" PRId32, s->died);
  sylva_stand_figure f[SYLVA_STAND_FIGURES];
  sylva_stand_figures(s, f);
  for (size_t i = 0; i < SYLVA_STAND_FIGURES; i++) {
    put_key(b, false, f[i].key, compact);
    sylva__strbuf_fixed(b, f[i].value, f[i].decimals);
  }
  sylva__strbuf_putc(b, '}');
}

void sylva__put_stem_stats(sylva__strbuf *b, const sylva_world *w, const sylva_stem_stats *s,
                           const sylva__stats_form *form, bool compact) {
  const char *label = sylva_world_plant_label(w, s->plant);
  sylva__strbuf_putc(b, '{');
  put_key(b, true, "plant", compact);
  sylva__strbuf_json_string(b, label ? label : "");
  put_key(b, false, "stem", compact);
  sylva__strbuf_printf(b, "%" PRId32, s->stem);
  if (form->years) { /* null for a stem of a species without years */
    put_key(b, false, "age", compact);
    if (s->age >= 0)
      sylva__strbuf_printf(b, "%" PRId32, s->age);
    else
      sylva__strbuf_puts(b, "null");
  }
  put_key(b, false, "height", compact);
  sylva__strbuf_fixed(b, s->height, 4);
  put_key(b, false, "dbh", compact);
  sylva__strbuf_fixed(b, s->dbh, 4);
  put_key(b, false, "crown_width", compact);
  sylva__strbuf_fixed(b, s->crown_width, 4);
  if (form->years) { /* the database's crown diameter is this same mean of extents */
    put_key(b, false, "crown_diameter", compact);
    sylva__strbuf_fixed(b, s->crown_width, 4);
  }
  put_key(b, false, "crown_base", compact);
  sylva__strbuf_fixed(b, s->crown_base, 4);
  if (form->years) {
    put_key(b, false, "crown_height", compact);
    sylva__strbuf_fixed(b, s->crown_height, 4);
  }
  put_key(b, false, "leaf_area", compact); /* m^2 (docs/model.md, "Foliage") */
  sylva__strbuf_fixed(b, s->leaf_area, 4);
  put_key(b, false, "crown_area", compact); /* m^2 (docs/model.md, "Canopy cover") */
  sylva__strbuf_fixed(b, s->crown_area, 4);
  put_key(b, false, "wood_volume", compact); /* m^3 (docs/model.md, "Wood and carbon") */
  sylva__strbuf_fixed(b, s->wood_volume, 6);
  /* kg; absent where they do not apply (no allometry, no density, no dbh) */
  const struct {
    const char *key;
    double v;
  } carbon[] = {{"biomass", s->biomass},   {"biomass_model", s->biomass_model},
                {"carbon", s->carbon},     {"co2", s->co2},
                {"co2_sequestered", s->co2_sequestered}};
  for (size_t i = 0; i < sizeof carbon / sizeof *carbon; i++) {
    if (!isfinite(carbon[i].v)) continue;
    put_key(b, false, carbon[i].key, compact);
    sylva__strbuf_fixed(b, carbon[i].v, 3);
  }
  put_key(b, false, "nodes", compact);
  sylva__strbuf_printf(b, "%" PRId64, s->nodes);
  put_key(b, false, "shed", compact);
  sylva__strbuf_printf(b, "%" PRId64, s->shed);
  if (form->conflicts) {
    put_key(b, false, "pruned", compact);
    sylva__strbuf_printf(b, "%" PRId64, s->pruned);
  }
  put_key(b, false, "light", compact);
  sylva__strbuf_fixed(b, s->light, 3);
  put_key(b, false, "cap", compact);
  sylva__strbuf_printf(b, "%d", s->cap);
  put_key(b, false, "finished", compact);
  sylva__strbuf_puts(b, s->finished ? "true" : "false");
  if (form->stand) { /* docs/model.md, "Stands" */
    put_key(b, false, "alive", compact);
    sylva__strbuf_puts(b, s->alive ? "true" : "false");
    put_key(b, false, "died", compact); /* a calendar year in a run with a start year */
    if (s->died >= 0)
      sylva__strbuf_printf(b, "%" PRId32, s->died + form->start_year);
    else
      sylva__strbuf_puts(b, "null");
    put_key(b, false, "vigour", compact);
    sylva__strbuf_fixed(b, s->vigour, 4);
  }
  if (form->conflicts) {
    sylva_conflicts c = sylva_world_stem_conflicts(w, sylva_world_stem_index(w, s->plant, s->stem));
    put_key(b, false, "zones", compact);
    put_zones(b, w, &c, form->start_year, compact);
    put_key(b, false, "clearance", compact);
    put_clearance(b, w, &c, compact);
  }
  sylva__strbuf_putc(b, '}');
}

char *sylva_encode_stats_line(const sylva_world *w, const sylva_journal *j, double elapsed_ms,
                              int start_year) {
  sylva__strbuf b = {0};
  sylva__stats_form form = sylva__stats_form_of(w, start_year);
  sylva__strbuf_printf(&b, "{\"iteration\": %d, ", j->iteration);
  if (start_year) sylva__strbuf_printf(&b, "\"year\": %d, ", start_year + j->iteration);
  sylva__strbuf_puts(&b, "\"elapsed_ms\": ");
  sylva__strbuf_fixed(&b, elapsed_ms, 1);
  sylva__strbuf_puts(&b, ", \"stems\": [");
  for (size_t i = 0; i < j->stem_count; i++) {
    if (i) sylva__strbuf_puts(&b, ", ");
    sylva__put_stem_stats(&b, w, &j->stats[i], &form, false);
  }
  sylva__strbuf_puts(&b, "], \"canopy_cover\": "); /* docs/model.md, "Canopy cover" */
  sylva__strbuf_fixed(&b, j->canopy_cover, 4);
  if (form.stand) {
    sylva__strbuf_puts(&b, ", \"stand\": ");
    sylva__put_stand(&b, &j->stand, false);
  }
  sylva__strbuf_putc(&b, '}');
  return sylva__strbuf_finish(&b);
}

char *sylva_encode_done_line(int iterations, const char *reason) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"done\": true, \"iterations\": %d, \"reason\": ", iterations);
  sylva__strbuf_json_string(&b, reason ? reason : "");
  sylva__strbuf_putc(&b, '}');
  return sylva__strbuf_finish(&b);
}

void sylva__put_vec3(sylva__strbuf *b, const double v[3]) {
  for (int i = 0; i < 3; i++) {
    sylva__strbuf_putc(b, i ? ',' : '[');
    sylva__strbuf_shortest(b, v[i]);
  }
  sylva__strbuf_putc(b, ']');
}

void sylva__put_radius(sylva__strbuf *b, float radius) {
  sylva__strbuf_fixed(b, radius, SYLVA__RADIUS_DECIMALS);
}

void sylva__put_node_geometry(sylva__strbuf *b, const sylva_node_info *n) {
  sylva__strbuf_fixed(b, n->x, SYLVA__POSITION_DECIMALS);
  sylva__strbuf_putc(b, ',');
  sylva__strbuf_fixed(b, n->y, SYLVA__POSITION_DECIMALS);
  sylva__strbuf_putc(b, ',');
  sylva__strbuf_fixed(b, n->z, SYLVA__POSITION_DECIMALS);
  sylva__strbuf_putc(b, ',');
  sylva__put_radius(b, n->radius);
}

static void put_node(sylva__strbuf *b, const sylva_node_info *n) {
  sylva__strbuf_printf(b, "[%" PRId32 ",%" PRId32 ",", n->id, n->parent);
  sylva__put_node_geometry(b, n);
  sylva__strbuf_printf(b, ",%" PRId32 "]", n->birth);
}

void sylva__put_world_body(sylva__strbuf *b, const sylva_world *w, bool with_nodes) {
  const sylva_world_def *def = sylva_world_get_def(w);
  size_t node_count = with_nodes ? sylva_world_node_count(w) : 0;
  int stem_count = sylva_world_stem_count(w);
  /* One pass over the nodes, then a counting sort by global stem; nodes keep their
   * id order within a stem. */
  sylva_node_info *nodes = malloc((node_count ? node_count : 1) * sizeof *nodes);
  size_t *order = malloc((node_count ? node_count : 1) * sizeof *order);
  size_t *start = calloc((size_t)stem_count + 1, sizeof *start);
  size_t *next = malloc(((size_t)stem_count + 1) * sizeof *next);
  if (!nodes || !order || !start || !next) goto fail;
  for (size_t i = 0; i < node_count; i++) {
    sylva_world_node_at(w, i, &nodes[i]);
    int s = sylva_world_stem_index(w, nodes[i].plant, nodes[i].stem);
    if (s < 0 || s >= stem_count) goto fail;
    start[s + 1]++;
  }
  for (int s = 0; s < stem_count; s++) start[s + 1] += start[s];
  memcpy(next, start, ((size_t)stem_count + 1) * sizeof *next);
  for (size_t i = 0; i < node_count; i++)
    order[next[sylva_world_stem_index(w, nodes[i].plant, nodes[i].stem)]++] = i;

  if (!sylva__strbuf_reserve(b, node_count * 48 + 256)) goto fail;
  sylva__strbuf_puts(b, "\"voxel\":");
  sylva__strbuf_shortest(b, def->voxel);
  sylva__strbuf_puts(b, ",\"world\":{\"min\":");
  sylva__put_vec3(b, def->min);
  sylva__strbuf_puts(b, ",\"max\":");
  sylva__put_vec3(b, def->max);
  sylva__strbuf_puts(b, "},\"obstacles\":[");
  int obstacles = sylva_world_obstacle_count(w);
  for (int i = 0; i < obstacles; i++) {
    int id;
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, i, &id, &o);
    if (i) sylva__strbuf_putc(b, ',');
    sylva__put_obstacle(b, &o, true);
  }
  sylva__strbuf_puts(b, "],\"plants\":[");
  int plants = sylva_world_plant_count(w);
  for (int p = 0; p < plants; p++) {
    const char *label = sylva_world_plant_label(w, p);
    sylva__strbuf_puts(b, p ? ",{\"id\":" : "{\"id\":");
    sylva__strbuf_json_string(b, label ? label : "");
    sylva__strbuf_puts(b, ",\"stems\":[");
    int stems = sylva_world_plant_stem_count(w, p);
    for (int k = 0; k < stems; k++) {
      int s = sylva_world_stem_index(w, p, k);
      double root[3];
      sylva_world_stem_root(w, s, root);
      sylva__strbuf_puts(b, k ? ",{\"root\":" : "{\"root\":");
      sylva__put_vec3(b, root);
      if (with_nodes) {
        sylva__strbuf_puts(b, ",\"nodes\":[");
        for (size_t i = start[s]; i < start[s + 1]; i++) {
          if (i > start[s]) sylva__strbuf_putc(b, ',');
          put_node(b, &nodes[order[i]]);
        }
        sylva__strbuf_putc(b, ']');
      }
      sylva__strbuf_putc(b, '}');
    }
    sylva__strbuf_puts(b, "]}");
  }
  sylva__strbuf_putc(b, ']');
  free(nodes);
  free(order);
  free(start);
  free(next);
  return;

fail:
  /* Out of memory, or a node of an unknown stem: either way no skeleton. */
  b->failed = true;
  free(nodes);
  free(order);
  free(start);
  free(next);
}

char *sylva_encode_skeleton(const sylva_world *w) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"format\":\"sylva.skeleton/1\",\"iteration\":%d,",
                       sylva_world_iteration(w));
  sylva__put_world_body(&b, w, true);
  sylva__strbuf_puts(&b, "}\n");
  return sylva__strbuf_finish(&b);
}
