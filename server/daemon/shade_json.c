/* The daemon's shade layer; see shade_json.h. */
#include "shade_json.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "server_error.h"
#include "sylva/scenario.h"

shade_request shade_request_default(void) {
  return (shade_request){.month = 7, .day = 21, .from = 10 * 60, .to = 16 * 60};
}

int shade_request_arg(shade_request *q, const char *key, const char *value, char *err,
                      size_t errlen) {
  char why[256];
  int rc;
  if (strcmp(key, "date") == 0)
    rc = shade_parse_date(value, &q->month, &q->day, why, sizeof why);
  else
    rc = shade_parse_time(value, strcmp(key, "from") == 0 ? &q->from : &q->to, why, sizeof why);
  return rc ? server_fail(err, errlen, SERVER_EINPUT, "%s: %s", key, why) : SERVER_OK;
}

int shade_request_check(const shade_request *q, char *err, size_t errlen) {
  if (q->to > q->from) return SERVER_OK;
  return server_fail(err, errlen, SERVER_EINPUT, "to: %02d:%02d is not after from (%02d:%02d)",
                     q->to / 60, q->to % 60, q->from / 60, q->from % 60);
}

/* The site of the run's stored scenario: SERVER_EINPUT when its light is not a
 * site's (the sun needs a latitude). */
static int site_of_run(store *st, int64_t run, shade_site *site, char *err, size_t errlen) {
  char *json = NULL, why[512];
  if (store_run_scenario(st, run, &json))
    return server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
  sylva_scenario *s = NULL;
  int rc = sylva_scenario_parse(json, strlen(json), &s, why, sizeof why);
  free(json);
  if (rc) return server_fail(err, errlen, SERVER_EFAIL, "the run's stored scenario: %s", why);
  rc = SERVER_OK;
  if (!shade_site_of(s, site))
    rc = server_fail(err, errlen, SERVER_EINPUT,
                     "run: its light has no site (light.latitude, with \"sky\": \"site\"): "
                     "the sun's hours need a latitude");
  sylva_scenario_free(s);
  return rc;
}

/* A number of hours with at most two decimals, without trailing zeros. */
static void put_hours(FILE *f, double h) {
  char buf[32];
  snprintf(buf, sizeof buf, "%.2f", h > 0 ? h : 0.0);
  size_t n = strlen(buf);
  while (buf[n - 1] == '0') n--;
  if (buf[n - 1] == '.') n--;
  fwrite(buf, 1, n, f);
}

/* A JSON string (cJSON quotes it). */
static int put_string(FILE *f, const char *s) {
  cJSON *item = cJSON_CreateString(s);
  char *text = item ? cJSON_PrintUnformatted(item) : NULL;
  cJSON_Delete(item);
  if (!text) return SERVER_ENOMEM;
  fputs(text, f);
  cJSON_free(text);
  return SERVER_OK;
}

/* The cells [first, first + count) as an array of the hours the plants add. */
static void put_added(FILE *f, const shade_result *r, size_t first, size_t count) {
  fputc('[', f);
  for (size_t i = 0; i < count; i++) {
    if (i) fputc(',', f);
    const shade_cell *c = &r->cells[first + i];
    put_hours(f, c->open - c->with);
  }
  fputc(']', f);
}

/* A unit vector's x and y, with -0 written as 0. */
static void put_xy(FILE *f, const double v[2]) {
  fprintf(f, "[%.17g,%.17g]", v[0] + 0.0, v[1] + 0.0);
}

/* The faces' part: per face with cells, its obstacle, its face, its grid (nu cells
 * along it, fastest, by nz up it), the centre of its first cell, which way its cells
 * run, its outward normal and its cells' width along it. */
static int put_faces(FILE *f, const shade_result *r, const sylva_world *w) {
  fputs(",\"faces\":[", f);
  bool any = false;
  for (int s = 0; s < r->surface_count; s++) {
    const shade_surface *sf = &r->surfaces[s];
    if (sf->face < 0 || sf->count == 0) continue;
    const shade_cell *c0 = &r->cells[sf->first];
    size_t nu = 1;
    while (nu < sf->count && r->cells[sf->first + nu].p[2] == c0->p[2]) nu++;
    sylva_obstacle_def o;
    if (sylva_world_obstacle(w, sf->obstacle, &o) != 0) continue;
    fputs(any ? ",{\"obstacle\":" : "{\"obstacle\":", f);
    any = true;
    if (put_string(f, o.label)) return SERVER_ENOMEM;
    fprintf(f, ",\"face\":\"%s\",\"nu\":%zu,\"nz\":%zu,\"first\":[%.4f,%.4f,%.4f],\"along\":",
            sf->face_name, nu, sf->count / nu, c0->p[0], c0->p[1], c0->p[2]);
    put_xy(f, sf->along);
    fputs(",\"normal\":", f);
    put_xy(f, sf->normal);
    fprintf(f, ",\"du\":%.17g,\"added\":", sf->width);
    put_added(f, r, sf->first, sf->count);
    fputc('}', f);
  }
  fputc(']', f);
  return SERVER_OK;
}

static int write_result(FILE *f, const shade_result *r, const sylva_world *w,
                        const shade_request *q, int start_year) {
  double max = 0;
  for (size_t i = 0; i < r->cell_count; i++)
    if (r->cells[i].open - r->cells[i].with > max) max = r->cells[i].open - r->cells[i].with;
  fprintf(f, "{\"iteration\":%d,\"year\":", q->iteration);
  if (start_year > 0) fprintf(f, "%d", start_year + q->iteration);
  else fputs("null", f);
  fprintf(f,
          ",\"date\":\"%02d-%02d\",\"from\":\"%02d:%02d\",\"to\":\"%02d:%02d\",\"step\":%d,"
          "\"voxel\":%.17g,\"origin\":[%.17g,%.17g,%.17g],\"nx\":%d,\"ny\":%d,\"max\":",
          q->month, q->day, q->from / 60, q->from % 60, q->to / 60, q->to % 60, r->day.step,
          r->voxel, r->min[0], r->min[1], r->min[2], r->nx, r->ny);
  put_hours(f, max);
  fputs(",\"ground\":", f);
  put_added(f, r, 0, (size_t)r->nx * (size_t)r->ny);
  int rc = put_faces(f, r, w);
  fputs("}\n", f);
  return rc;
}

int shade_json_write(FILE *f, store *st, const shade_request *q, char *err, size_t errlen) {
  shade_site site;
  int rc = site_of_run(st, q->run, &site, err, errlen);
  if (rc) return rc;
  int start_year = 0;
  bool years = false;
  if (store_run_calendar(st, q->run, &start_year, &years))
    return server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
  sylva_world *w = NULL;
  if (store_world_at(st, q->run, q->iteration, NULL, &w))
    return server_fail(err, errlen, SERVER_EFAIL, "%s", store_error(st));
  shade_day day = shade_default_day();
  day.month = q->month;
  day.day = q->day;
  day.from = q->from;
  day.to = q->to;
  day.year = start_year > 0 ? start_year + q->iteration : day.year;
  shade_result r;
  rc = shade_compute(w, &site, &day, NULL, &r, err, errlen);
  if (!rc) {
    errno = 0;
    rc = write_result(f, &r, w, q, start_year);
    if (!rc && (ferror(f) || fflush(f) != 0))
      rc = server_fail(err, errlen, SERVER_EWRITE, "temporary file: %s",
                       strerror(errno ? errno : EIO));
    else if (rc)
      server_fail(err, errlen, rc, "out of memory");
  }
  shade_result_free(&r);
  sylva_world_destroy(w);
  return rc;
}
