/* The scenario's `light` key (docs/scenario.md, "light"): which sky lights the
 * site. "zenith" (the default) is the paper's light from straight above; "site"
 * is the sun's path at a latitude over a season plus an overcast sky, as weighted
 * directions (sky.c) that obstacles block from any side. */
#include <math.h>
#include <string.h>

#include "scenario_parts.h"
#include "strbuf.h"

static const char *const light_keys[] = {"sky",     "latitude", "north",     "season",
                                         "diffuse", "samples",  "longitude", "utc_offset"};

/* A member that only a site sky has: every key of light_keys but the first, "sky". */
static int only_site(sylva__parser *p, const cJSON *item) {
  for (size_t k = 1; k < sizeof light_keys / sizeof light_keys[0]; k++)
    if (cJSON_GetObjectItemCaseSensitive(item, light_keys[k]))
      return sylva__fail_at_key(p, light_keys[k], "only with \"sky\": \"site\"");
  return 0;
}

static int parse_north(sylva__parser *p, const cJSON *v, double north[2]) {
  size_t old = sylva__ptr_push(p, "north");
  int rc = 0;
  if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2) {
    rc = sylva__fail(p, "expected [x, y], the direction of north in the x-y plane");
  } else {
    for (int i = 0; i < 2 && !rc; i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      rc = sylva__want_number(p, cJSON_GetArrayItem(v, i), &north[i]);
      sylva__ptr_pop(p, o2);
    }
    if (!rc && !(hypot(north[0], north[1]) > 1e-9))
      rc = sylva__fail(p, "has no length; give the direction of north, e.g. [0, 1]");
  }
  sylva__ptr_pop(p, old);
  return rc;
}

static int parse_season(sylva__parser *p, const cJSON *v, int *first, int *last) {
  size_t old = sylva__ptr_push(p, "season");
  int rc = 0;
  double d[2] = {0, 0};
  if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2) {
    rc = sylva__fail(p, "expected [first, last], days of the year from 1 to 365");
  } else {
    for (int i = 0; i < 2 && !rc; i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      rc = sylva__want_integer(p, cJSON_GetArrayItem(v, i), 1, 365, &d[i]);
      sylva__ptr_pop(p, o2);
    }
    if (!rc && d[0] > d[1])
      rc = sylva__fail(p, "is empty: the first day (%g) comes after the last (%g)", d[0], d[1]);
  }
  *first = (int)d[0];
  *last = (int)d[1];
  sylva__ptr_pop(p, old);
  return rc;
}

/* "longitude" and "utc_offset": both or neither (clock times for `sylva shade`). */
static int parse_clock(sylva__parser *p, const cJSON *item, sylva_scenario_light *out) {
  const cJSON *lon = cJSON_GetObjectItemCaseSensitive(item, "longitude");
  const cJSON *utc = cJSON_GetObjectItemCaseSensitive(item, "utc_offset");
  if (!lon && !utc) return 0;
  if (!lon || !utc)
    return sylva__fail_at_key(p, lon ? "utc_offset" : "longitude",
                              "required with \"%s\": the site's clock needs both",
                              lon ? "longitude" : "utc_offset");
  size_t old = sylva__ptr_push(p, "longitude");
  int rc = sylva__want_number(p, lon, &out->longitude);
  if (!rc && !(out->longitude >= -180.0 && out->longitude <= 180.0))
    rc = sylva__fail(p, "must be from -180 to 180 degrees (east positive), got %g", out->longitude);
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  old = sylva__ptr_push(p, "utc_offset");
  rc = sylva__want_number(p, utc, &out->utc_offset);
  if (!rc && !(out->utc_offset >= -14.0 && out->utc_offset <= 14.0))
    rc = sylva__fail(p, "must be from -14 to 14 hours, got %g", out->utc_offset);
  sylva__ptr_pop(p, old);
  out->clock = rc == 0;
  return rc;
}

int sylva__parse_light(sylva__parser *p, const cJSON *item, sylva_scenario_light *out) {
  *out = (sylva_scenario_light){.site = false};
  size_t old = sylva__ptr_push(p, "light");
  int rc = sylva__want_object(p, item);
  if (!rc) rc = sylva__check_keys(p, item, light_keys, sizeof light_keys / sizeof light_keys[0]);
  const char *sky = "zenith";
  const cJSON *v;
  if (!rc && (v = cJSON_GetObjectItemCaseSensitive(item, "sky"))) {
    size_t o2 = sylva__ptr_push(p, "sky");
    rc = sylva__want_string(p, v, &sky);
    if (!rc && strcmp(sky, "zenith") != 0 && strcmp(sky, "site") != 0) {
      char q[80];
      rc = sylva__fail(p, "expected \"zenith\" or \"site\", got %s", sylva__quote(q, sky));
    }
    sylva__ptr_pop(p, o2);
  }
  if (!rc && strcmp(sky, "zenith") == 0) rc = only_site(p, item);
  if (!rc && strcmp(sky, "site") == 0) {
    sylva_sky_def *d = &out->sky;
    *d = (sylva_sky_def){.north = {0, 1}, .first_day = 1, .last_day = 365,
                         .diffuse = SYLVA_SITE_DIFFUSE, .samples = SYLVA_SITE_SAMPLES};
    out->site = true;
    if (!(v = cJSON_GetObjectItemCaseSensitive(item, "latitude"))) {
      rc = sylva__fail_at_key(p, "latitude", "required with \"sky\": \"site\": degrees, north positive");
    } else {
      size_t o2 = sylva__ptr_push(p, "latitude");
      rc = sylva__want_number(p, v, &d->latitude);
      if (!rc && !(d->latitude >= -90.0 && d->latitude <= 90.0))
        rc = sylva__fail(p, "must be from -90 to 90 degrees, got %g", d->latitude);
      sylva__ptr_pop(p, o2);
    }
    if (!rc && (v = cJSON_GetObjectItemCaseSensitive(item, "north")))
      rc = parse_north(p, v, d->north);
    if (!rc && (v = cJSON_GetObjectItemCaseSensitive(item, "season")))
      rc = parse_season(p, v, &d->first_day, &d->last_day);
    if (!rc && (v = cJSON_GetObjectItemCaseSensitive(item, "diffuse"))) {
      size_t o2 = sylva__ptr_push(p, "diffuse");
      rc = sylva__want_number(p, v, &d->diffuse);
      if (!rc && !(d->diffuse >= 0.0 && d->diffuse <= 1.0))
        rc = sylva__fail(p, "must be from 0 to 1 (the overcast sky's share), got %g", d->diffuse);
      sylva__ptr_pop(p, o2);
    }
    if (!rc) rc = parse_clock(p, item, out);
    if (!rc && (v = cJSON_GetObjectItemCaseSensitive(item, "samples"))) {
      size_t o2 = sylva__ptr_push(p, "samples");
      double n = 0;
      rc = sylva__want_integer(p, v, 1, SYLVA_MAX_SKY, &n);
      d->samples = (int)n;
      sylva__ptr_pop(p, o2);
    }
  }
  sylva__ptr_pop(p, old);
  return rc;
}

void sylva__put_light(sylva__strbuf *b, const sylva_scenario_light *l) {
  const sylva_sky_def *d = &l->sky;
  sylva__strbuf_puts(b, "{\"sky\": \"site\", \"latitude\": ");
  sylva__strbuf_shortest(b, d->latitude);
  sylva__strbuf_puts(b, ", \"north\": [");
  sylva__strbuf_shortest(b, d->north[0]);
  sylva__strbuf_puts(b, ", ");
  sylva__strbuf_shortest(b, d->north[1]);
  sylva__strbuf_printf(b, "], \"season\": [%d, %d], \"diffuse\": ", d->first_day, d->last_day);
  sylva__strbuf_shortest(b, d->diffuse);
  sylva__strbuf_printf(b, ", \"samples\": %d", d->samples);
  if (l->clock) {
    sylva__strbuf_puts(b, ", \"longitude\": ");
    sylva__strbuf_shortest(b, l->longitude);
    sylva__strbuf_puts(b, ", \"utc_offset\": ");
    sylva__strbuf_shortest(b, l->utc_offset);
  }
  sylva__strbuf_puts(b, "}");
}
