/* Deterministic encoders: stats lines, the done line and the skeleton. */
#include "sylva/encode.h"

#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

char *sylva_encode_stats_line(const sylva_world *w, const sylva_journal *j, double elapsed_ms) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"iteration\": %d, \"elapsed_ms\": ", j->iteration);
  sylva__strbuf_fixed(&b, elapsed_ms, 1);
  sylva__strbuf_puts(&b, ", \"stems\": [");
  for (size_t i = 0; i < j->stem_count; i++) {
    const sylva_stem_stats *s = &j->stats[i];
    const char *label = sylva_world_plant_label(w, s->plant);
    sylva__strbuf_puts(&b, i ? ", {\"plant\": " : "{\"plant\": ");
    sylva__strbuf_json_string(&b, label ? label : "");
    sylva__strbuf_printf(&b, ", \"stem\": %" PRId32 ", \"height\": ", s->stem);
    sylva__strbuf_fixed(&b, s->height, 4);
    sylva__strbuf_puts(&b, ", \"dbh\": ");
    sylva__strbuf_fixed(&b, s->dbh, 4);
    sylva__strbuf_puts(&b, ", \"crown_width\": ");
    sylva__strbuf_fixed(&b, s->crown_width, 4);
    sylva__strbuf_puts(&b, ", \"crown_base\": ");
    sylva__strbuf_fixed(&b, s->crown_base, 4);
    sylva__strbuf_printf(&b, ", \"nodes\": %" PRId64 ", \"shed\": %" PRId64 ", \"light\": ",
                         s->nodes, s->shed);
    sylva__strbuf_fixed(&b, s->light, 3);
    sylva__strbuf_printf(&b, ", \"cap\": %d, \"finished\": %s}", s->cap,
                         s->finished ? "true" : "false");
  }
  sylva__strbuf_puts(&b, "]}");
  return sylva__strbuf_finish(&b);
}

char *sylva_encode_done_line(int iterations, const char *reason) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"done\": true, \"iterations\": %d, \"reason\": ", iterations);
  sylva__strbuf_json_string(&b, reason ? reason : "");
  sylva__strbuf_putc(&b, '}');
  return sylva__strbuf_finish(&b);
}

static void put_vec(sylva__strbuf *b, const double v[3]) {
  for (int i = 0; i < 3; i++) {
    sylva__strbuf_putc(b, i ? ',' : '[');
    sylva__strbuf_shortest(b, v[i]);
  }
  sylva__strbuf_putc(b, ']');
}

static void put_node(sylva__strbuf *b, const sylva_node_info *n) {
  sylva__strbuf_printf(b, "[%" PRId32 ",%" PRId32 ",", n->id, n->parent);
  sylva__strbuf_fixed(b, n->x, 4);
  sylva__strbuf_putc(b, ',');
  sylva__strbuf_fixed(b, n->y, 4);
  sylva__strbuf_putc(b, ',');
  sylva__strbuf_fixed(b, n->z, 4);
  sylva__strbuf_putc(b, ',');
  sylva__strbuf_fixed(b, n->radius, 5);
  sylva__strbuf_printf(b, ",%" PRId32 "]", n->birth);
}

char *sylva_encode_skeleton(const sylva_world *w) {
  const sylva_world_def *def = sylva_world_get_def(w);
  size_t node_count = sylva_world_node_count(w);
  int stem_count = sylva_world_stem_count(w);
  /* One pass over the nodes, then a counting sort by global stem; nodes keep their
   * id order within a stem. */
  sylva_node_info *nodes = malloc((node_count ? node_count : 1) * sizeof *nodes);
  size_t *order = malloc((node_count ? node_count : 1) * sizeof *order);
  size_t *start = calloc((size_t)stem_count + 1, sizeof *start);
  sylva__strbuf b = {0};
  if (!nodes || !order || !start) goto fail;
  for (size_t i = 0; i < node_count; i++) {
    sylva_world_node_at(w, i, &nodes[i]);
    int s = sylva_world_stem_index(w, nodes[i].plant, nodes[i].stem);
    if (s < 0 || s >= stem_count) goto fail;
    start[s + 1]++;
  }
  for (int s = 0; s < stem_count; s++) start[s + 1] += start[s];
  {
    size_t *next = malloc(((size_t)stem_count + 1) * sizeof *next);
    if (!next) goto fail;
    memcpy(next, start, ((size_t)stem_count + 1) * sizeof *next);
    for (size_t i = 0; i < node_count; i++)
      order[next[sylva_world_stem_index(w, nodes[i].plant, nodes[i].stem)]++] = i;
    free(next);
  }

  if (!sylva__strbuf_reserve(&b, node_count * 48 + 256)) goto fail;
  sylva__strbuf_printf(&b, "{\"format\":\"sylva.skeleton/1\",\"iteration\":%d,\"voxel\":",
                       sylva_world_iteration(w));
  sylva__strbuf_shortest(&b, def->voxel);
  sylva__strbuf_puts(&b, ",\"world\":{\"min\":");
  put_vec(&b, def->min);
  sylva__strbuf_puts(&b, ",\"max\":");
  put_vec(&b, def->max);
  sylva__strbuf_puts(&b, "},\"obstacles\":[");
  int obstacles = sylva_world_obstacle_count(w);
  for (int i = 0; i < obstacles; i++) {
    int id;
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, i, &id, &o);
    sylva__strbuf_puts(&b, i ? ",{\"id\":" : "{\"id\":");
    sylva__strbuf_json_string(&b, o.label ? o.label : "");
    sylva__strbuf_puts(&b, ",\"kind\":\"box\",\"min\":");
    put_vec(&b, o.min);
    sylva__strbuf_puts(&b, ",\"max\":");
    put_vec(&b, o.max);
    sylva__strbuf_putc(&b, '}');
  }
  sylva__strbuf_puts(&b, "],\"plants\":[");
  int plants = sylva_world_plant_count(w);
  for (int p = 0; p < plants; p++) {
    const char *label = sylva_world_plant_label(w, p);
    sylva__strbuf_puts(&b, p ? ",{\"id\":" : "{\"id\":");
    sylva__strbuf_json_string(&b, label ? label : "");
    sylva__strbuf_puts(&b, ",\"stems\":[");
    int stems = sylva_world_plant_stem_count(w, p);
    for (int k = 0; k < stems; k++) {
      int s = sylva_world_stem_index(w, p, k);
      double root[3];
      sylva_world_stem_root(w, s, root);
      sylva__strbuf_puts(&b, k ? ",{\"root\":" : "{\"root\":");
      put_vec(&b, root);
      sylva__strbuf_puts(&b, ",\"nodes\":[");
      for (size_t i = start[s]; i < start[s + 1]; i++) {
        if (i > start[s]) sylva__strbuf_putc(&b, ',');
        put_node(&b, &nodes[order[i]]);
      }
      sylva__strbuf_puts(&b, "]}");
    }
    sylva__strbuf_puts(&b, "]}");
  }
  sylva__strbuf_puts(&b, "]}\n");
  free(nodes);
  free(order);
  free(start);
  return sylva__strbuf_finish(&b);

fail:
  free(nodes);
  free(order);
  free(start);
  sylva__strbuf_free(&b);
  return NULL;
}
