/* `sylva shade`: the hours of direct sun on a site's ground and on its solid
 * obstacles' vertical faces over one day, without the plants and with them, for a
 * stored iteration or a scenario as planted (shade.h; docs/cli.md, "shade"). */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include "cli_input.h"
#include "cli_store.h"
#include "commands.h"
#include "options.h"
#include "outfile.h"
#include "server_error.h"
#include "shade.h"
#include "sylva/scenario.h"

enum { OPT_DB, OPT_NAME, OPT_ITERATION, OPT_YEAR, OPT_DATE, OPT_FROM, OPT_TO, OPT_STEP,
       OPT_SURFACE, OPT_OUT, OPT_HELP, OPT_COUNT };

static const cli_option shade_cli_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store holding the run"},
    [OPT_NAME] = {"name", 0, "NAME", "the stored run"},
    [OPT_ITERATION] = {"iteration", 0, "T", "the iteration (default: the last stored)"},
    [OPT_YEAR] = {"year", 0, "Y", "the iteration of calendar year Y (start_year + T)"},
    [OPT_DATE] = {"date", 0, "MM-DD", "the day (required)"},
    [OPT_FROM] = {"from", 0, "HH:MM", "the first time (default 00:00)"},
    [OPT_TO] = {"to", 0, "HH:MM", "the end, not sampled (default 24:00)"},
    [OPT_STEP] = {"step", 0, "MIN", "minutes between samples, 1 to 1440 (default 10)"},
    [OPT_SURFACE] = {"surface", 0, "S",
                     "only 'ground' or one face, OBSTACLE_ID:FACE: +x|-x|+y|-y of a box, "
                     "e0, e1, ... (its footprint's edges) of a prism"},
    [OPT_OUT] = {"output", 'o', "OUT", "the file to write: OUT.csv, OUT.json or OUT.png (required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void shade_usage(FILE *f) {
  fputs("Usage: sylva shade --db FILE --name NAME [--iteration T | --year Y] --date MM-DD\n"
        "                   [--from HH:MM] [--to HH:MM] [--step MIN] [--surface S] -o OUT\n"
        "       sylva shade SCENARIO.json --date MM-DD [--from HH:MM] [--to HH:MM]\n"
        "                   [--step MIN] [--surface S] -o OUT\n"
        "\n"
        "Hours of direct sun on one day on every voxel-sized cell of the ground and of\n"
        "the vertical faces of the solid obstacles, without the plants (sun_hours_open)\n"
        "and with them (sun_hours: the leaves pass exp(-0.5 LAD path) of the sun).\n"
        "A stored iteration (a non-stored one is regrown from the snapshot before it),\n"
        "or a scenario as planted. The site's light must give \"latitude\". Times are\n"
        "local solar time (12:00 the sun's transit), or clock times when the light\n"
        "gives \"longitude\" and \"utc_offset\". Samples at from, from + step, ... before\n"
        "to, each counting step minutes.\n"
        "The format follows OUT's extension:\n"
        "  .csv   one row per cell: x,y,z,surface,sun_hours_open,sun_hours\n"
        "  .json  the day's summary per surface (ground, OBSTACLE_ID:FACE)\n"
        "  .png   the plan of the ground's tree shade hours with a legend\n"
        "The summary is also printed as the last line of stdout. OUT is written to\n"
        "OUT.tmp, then renamed.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, shade_cli_options, OPT_COUNT);
}

typedef enum shade_format { SHADE_CSV, SHADE_JSON, SHADE_PNG } shade_format;

typedef struct shade_args {
  const char *db, *name, *scenario, *out, *surface;
  uint64_t iteration, year;
  bool has_iteration, has_year, has_date;
  shade_day day;
  shade_format format;
} shade_args;

static bool ends_with(const char *s, const char *tail) {
  size_t n = strlen(s), t = strlen(tail);
  return n > t && strcmp(s + n - t, tail) == 0;
}

static int parse_args(int argc, char **argv, shade_args *a) {
  cli_parser p;
  cli_parser_init(&p, "shade", shade_cli_options, OPT_COUNT, argc, argv);
  const char *arg;
  char err[256];
  uint64_t step = 0;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: a->db = arg; break;
    case OPT_NAME: a->name = arg; break;
    case OPT_ITERATION:
      if (cli_parse_u64("shade", "iteration", arg, 0, SYLVA_SCENARIO_MAX_ITERATIONS, &a->iteration))
        return CLI_EXIT_USAGE;
      a->has_iteration = true;
      break;
    case OPT_YEAR:
      if (cli_parse_u64("shade", "year", arg, 1, 100000, &a->year)) return CLI_EXIT_USAGE;
      a->has_year = true;
      break;
    case OPT_DATE:
      if (shade_parse_date(arg, &a->day.month, &a->day.day, err, sizeof err))
        return cli_usage_error("shade", "--date: %s", err);
      a->has_date = true;
      break;
    case OPT_FROM:
      if (shade_parse_time(arg, &a->day.from, err, sizeof err))
        return cli_usage_error("shade", "--from: %s", err);
      break;
    case OPT_TO:
      if (shade_parse_time(arg, &a->day.to, err, sizeof err))
        return cli_usage_error("shade", "--to: %s", err);
      break;
    case OPT_STEP:
      if (cli_parse_u64("shade", "step", arg, 1, SHADE_DAY_MINUTES, &step)) return CLI_EXIT_USAGE;
      a->day.step = (int)step;
      break;
    case OPT_SURFACE: a->surface = arg; break;
    case OPT_OUT: a->out = arg; break;
    default:
      shade_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (argc - first > 1) return cli_usage_error("shade", "unexpected argument '%s'", argv[first + 1]);
  if (argc - first == 1) a->scenario = argv[first];
  if (a->scenario && (a->db || a->name || a->has_iteration || a->has_year))
    return cli_usage_error("shade", "--db, --name, --iteration and --year are for a stored run, "
                                    "not for SCENARIO.json (a scenario is shaded as planted)");
  if (!a->scenario && !a->db && !a->name)
    return cli_usage_error("shade", "expected --db FILE --name NAME, or SCENARIO.json");
  if (a->has_iteration && a->has_year)
    return cli_usage_error("shade", "--iteration and --year name the same thing: give one");
  if (!a->has_date) return cli_usage_error("shade", "--date MM-DD is required");
  if (a->day.from >= a->day.to)
    return cli_usage_error("shade", "--from %02d:%02d is not before --to %02d:%02d",
                           a->day.from / 60, a->day.from % 60, a->day.to / 60, a->day.to % 60);
  if (!a->out || !a->out[0]) return cli_usage_error("shade", "-o OUT is required");
  if (ends_with(a->out, ".csv")) a->format = SHADE_CSV;
  else if (ends_with(a->out, ".json")) a->format = SHADE_JSON;
  else if (ends_with(a->out, ".png")) a->format = SHADE_PNG;
  else return cli_usage_error("shade", "-o: '%s' does not end in .csv, .json or .png", a->out);
  if (a->format == SHADE_PNG && a->surface && strcmp(a->surface, "ground") != 0)
    return cli_usage_error("shade", "--surface %s: the plan (.png) shows the ground only",
                           a->surface);
  return CLI_PARSED;
}

/* The site of a scenario's light; exit 2 without a latitude. */
static int site_of(const char *where, const sylva_scenario *s, shade_site *site) {
  if (!shade_site_of(s, site)) {
    fprintf(stderr,
            "sylva: %s: the sun needs the site's latitude: the scenario's light has no "
            "\"latitude\" (light.latitude, with \"sky\": \"site\"; docs/scenario.md)\n",
            where);
    return CLI_EXIT_USAGE;
  }
  return CLI_EXIT_OK;
}

/* Computes and writes the shade of w. */
static int shade_world(const shade_args *a, const sylva_world *w, const shade_site *site,
                       const shade_day *day) {
  char err[512];
  shade_filter filter, *fp = NULL;
  if (a->surface) {
    if (shade_parse_surface(w, a->surface, &filter, err, sizeof err))
      return cli_usage_error("shade", "--surface: %s", err);
    fp = &filter;
  }
  cli_outfile o = {0};
  int rc = cli_outfile_open(&o, "-o", a->out, false);
  if (rc) return rc;
  shade_result r;
  int failed = shade_compute_threads(w, site, day, fp, 0, &r, err, sizeof err);
  if (!failed) {
    if (a->format == SHADE_CSV) failed = shade_write_csv(o.f, &r, err, sizeof err);
    else if (a->format == SHADE_JSON) failed = shade_write_summary(o.f, &r, err, sizeof err);
    else failed = shade_write_png(o.f, &r, w, err, sizeof err);
    if (failed == SERVER_EWRITE) fprintf(stderr, "sylva: %s: %s\n", a->out, err);
  }
  if (failed && failed != SERVER_EWRITE) fprintf(stderr, "sylva: shade: %s\n", err);
  rc = cli_outfile_close(&o, server_exit_status(failed));
  if (rc == CLI_EXIT_OK) {
    char e2[64];
    if (shade_write_summary(stdout, &r, e2, sizeof e2)) rc = CLI_EXIT_FAILURE;
  }
  shade_result_free(&r);
  return rc;
}

static int shade_stored(shade_args *a) {
  store *st;
  store_run r;
  int rc = cli_open_run("shade", a->db, a->name, &st, &r);
  if (rc) return rc;
  int at = r.last_iteration;
  if (a->has_year) {
    if (r.start_year <= 0) {
      fprintf(stderr, "sylva: %s: run \"%s\" has no start_year: give --iteration T, not --year\n",
              a->db, r.name);
      rc = CLI_EXIT_USAGE;
    } else if (a->year < (uint64_t)r.start_year ||
               a->year > (uint64_t)r.start_year + (uint64_t)r.last_iteration) {
      fprintf(stderr, "sylva: %s: run \"%s\" has no year %llu (it has %d to %d)\n", a->db, r.name,
              (unsigned long long)a->year, r.start_year, r.start_year + r.last_iteration);
      rc = CLI_EXIT_USAGE;
    } else {
      at = (int)(a->year - (uint64_t)r.start_year);
    }
  } else {
    rc = cli_stored_iteration(a->db, &r, a->has_iteration, a->iteration, &at);
  }
  sylva_scenario *s = NULL;
  shade_site site;
  if (rc == CLI_EXIT_OK) {
    char err[512];
    if (sylva_scenario_parse(r.scenario, strlen(r.scenario), &s, err, sizeof err)) {
      fprintf(stderr, "sylva: run \"%s\": its stored scenario: %s\n", r.name, err);
      rc = CLI_EXIT_FAILURE;
    }
  }
  if (rc == CLI_EXIT_OK) rc = site_of(a->name, s, &site);
  sylva_world *w = NULL;
  if (rc == CLI_EXIT_OK) rc = cli_store_world_at(st, &r, at, &w);
  a->day.year = r.start_year > 0 ? r.start_year + at : 2025;
  if (rc == CLI_EXIT_OK) rc = shade_world(a, w, &site, &a->day);
  if (w) sylva_world_destroy(w);
  sylva_scenario_free(s);
  store_run_free(&r);
  store_close(st);
  return rc;
}

static int shade_scenario(shade_args *a) {
  sylva_scenario *s;
  int rc = cli_input_scenario(a->scenario, 0, &s);
  if (rc) return rc;
  shade_site site;
  rc = site_of(a->scenario, s, &site);
  sylva_world *w = NULL;
  if (rc == CLI_EXIT_OK) rc = cli_input_world(a->scenario, s, &w);
  a->day.year = s->start_year > 0 ? s->start_year : 2025;
  if (rc == CLI_EXIT_OK) rc = shade_world(a, w, &site, &a->day);
  if (w) sylva_world_destroy(w);
  sylva_scenario_free(s);
  return rc;
}

int cmd_shade(int argc, char **argv) {
  shade_args a = {.day = shade_default_day()};
  int rc = parse_args(argc, argv, &a);
  if (rc != CLI_PARSED) return rc;
  rc = a.scenario ? shade_scenario(&a) : shade_stored(&a);
  /* cairo's and fontconfig's caches hold memory until the process ends; free them
   * so that leak checkers see none */
  cairo_debug_reset_static_data();
  FcFini();
  return rc;
}
