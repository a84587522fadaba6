/* `sylva site`: a scenario from GIS layers: buildings as prisms, clearance zones,
 * and a tree inventory as plants of library species with their ages, in one local
 * frame in metres (docs/cli.md, "site"; server/gis/). */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "options.h"
#include "outfile.h"
#include "server_error.h"
#include "site.h"
#include "site_write.h"
#include "sylva/scenario.h"
#include "sylva/world.h"

enum {
  OPT_BUILDINGS,
  OPT_BUILDINGS_CRS,
  OPT_HEIGHT_FIELD,
  OPT_HEIGHT_UNIT,
  OPT_LEVELS_FIELD,
  OPT_LEVEL_HEIGHT,
  OPT_DEFAULT_HEIGHT,
  OPT_BUILDING_ID,
  OPT_TREES,
  OPT_LAYER_CRS,
  OPT_XY_FIELDS,
  OPT_SPECIES_FIELD,
  OPT_DBH_FIELD,
  OPT_DBH_UNIT,
  OPT_ID_FIELD,
  OPT_KEEP,
  OPT_SPECIES_MAP,
  OPT_DEFAULT_DBH,
  OPT_ZONES,
  OPT_ZONES_CRS,
  OPT_ZONE_FIELD,
  OPT_BBOX,
  OPT_CRS,
  OPT_REGION,
  OPT_NAME,
  OPT_ITERATIONS,
  OPT_START_YEAR,
  OPT_RHO,
  OPT_OUT,
  OPT_HELP,
  OPT_COUNT
};

static const cli_option site_options_list[OPT_COUNT] = {
    [OPT_BUILDINGS] = {"buildings", 0, "FILE",
                       "building footprints (polygons), any format GDAL reads"},
    [OPT_BUILDINGS_CRS] = {"buildings-crs", 0, "CRS",
                           "their CRS where the file names none (default EPSG:4326)"},
    [OPT_HEIGHT_FIELD] = {"height-field", 0, "F", "the buildings' height field"},
    [OPT_HEIGHT_UNIT] = {"height-unit", 0, "m|ft", "its unit (default m)"},
    [OPT_LEVELS_FIELD] = {"levels-field", 0, "F", "the buildings' storeys field (where no height)"},
    [OPT_LEVEL_HEIGHT] = {"level-height", 0, "M", "metres a storey (default 3)"},
    [OPT_DEFAULT_HEIGHT] = {"default-height", 0, "M", "the height of a building without one"},
    [OPT_BUILDING_ID] = {"building-id-field", 0, "F", "the buildings' id field (default bldg-ROW)"},
    [OPT_TREES] = {"trees", 0, "FILE", "a tree inventory (points, or a table with --xy-fields)"},
    [OPT_LAYER_CRS] = {"layer-crs", 0, "CRS",
                       "the trees' CRS where the file names none (default EPSG:4326)"},
    [OPT_XY_FIELDS] = {"xy-fields", 0, "X,Y", "the trees' coordinate fields (a CSV)"},
    [OPT_SPECIES_FIELD] = {"species-field", 0, "F",
                           "the trees' species field (required with --trees)"},
    [OPT_DBH_FIELD] = {"dbh-field", 0, "F", "the trees' DBH field (required with --trees)"},
    [OPT_DBH_UNIT] = {"dbh-unit", 0, "cm|in", "its unit (default cm)"},
    [OPT_ID_FIELD] = {"id-field", 0, "F", "the trees' id field (default the row number)"},
    [OPT_KEEP] = {"keep", 0, "FIELD=VALUE", "only trees with this value (repeatable)"},
    [OPT_SPECIES_MAP] = {"species-map", 0, "MAP.csv",
                         "name,species: inventory names to library species"},
    [OPT_DEFAULT_DBH] = {"default-dbh", 0, "CM", "the DBH of a tree without one"},
    [OPT_ZONES] = {"zones", 0, "FILE", "clearance zones (polygons)"},
    [OPT_ZONES_CRS] = {"zones-crs", 0, "CRS",
                       "their CRS where the file names none (default EPSG:4326)"},
    [OPT_ZONE_FIELD] = {"zone-field", 0, "F", "the zones' height field, m (required with --zones)"},
    [OPT_BBOX] = {"bbox", 0, "W,S,E,N", "the site: lon/lat degrees; features outside are left out"},
    [OPT_CRS] = {"crs", 0, "CRS", "the frame's CRS, projected in metres (default: see --help)"},
    [OPT_REGION] = {"region", 0, "R", "the UTDB region (default: the nearest reference city's)"},
    [OPT_NAME] = {"name", 0, "NAME", "the scenario's name (default \"site\")"},
    [OPT_ITERATIONS] = {"iterations", 0, "N",
                        "the scenario's iterations, 1 to 100000 (default 10)"},
    [OPT_START_YEAR] = {"start-year", 0, "Y", "the scenario's start_year, 1 to 9999"},
    [OPT_RHO] = {"rho", 0, "M", "the plants' internode length, 0.01 to 2 m (default the species')"},
    [OPT_OUT] = {"output", 'o', "SITE.json", "the scenario to write (required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void site_usage(FILE *f) {
  fputs(
      "Usage: sylva site [--buildings FILE (--height-field F | --levels-field F | --default-height "
      "M)]\n"
      "                  [--trees FILE --species-field F --dbh-field F] [--zones FILE --zone-field "
      "F]\n"
      "                  [OPTIONS] -o SITE.json\n"
      "\n"
      "Writes a scenario from GIS layers (any vector format GDAL reads): building\n"
      "footprints as solid prisms, clearance zones as zone prisms, trees as plants of\n"
      "the species library with their ages from their DBH (the Urban Tree Database's\n"
      "dbh -> age equation). Everything is put in one local frame in metres, x east and\n"
      "y north, its origin at the site's centre: the frame's CRS is --crs, else the\n"
      "first layer's (buildings, zones, trees) when projected in metres, else the UTM\n"
      "zone of the site's centre. Features left out are counted by reason. The last\n"
      "line of stdout is a JSON summary. Bad input exits 2 and writes nothing.\n"
      "\n"
      "Options:\n",
      f);
  cli_print_options(f, site_options_list, OPT_COUNT);
}

/* A decimal number in (lo, hi] (lo_open) or [lo, hi]; a usage error otherwise. */
static int parse_real(const char *option, const char *text, double lo, double hi, bool lo_open,
                      const char *what, double *out) {
  char *end;
  errno = 0;
  double v = strtod(text, &end);
  if (end == text || *end || errno || !isfinite(v) || v > hi || v < lo || (lo_open && v == lo))
    return cli_usage_error("site", "--%s: '%s' is not %s", option, text, what);
  *out = v;
  return CLI_PARSED;
}

/* A unit: `base` (1) or `other` (`factor` base units). */
static int parse_unit(const char *option, const char *text, const char *base, const char *other,
                      double factor, double *out) {
  if (strcmp(text, base) == 0)
    *out = 1.0;
  else if (strcmp(text, other) == 0)
    *out = factor;
  else
    return cli_usage_error("site", "--%s: '%s' is not %s or %s", option, text, base, other);
  return CLI_PARSED;
}

/* W,S,E,N in degrees. */
static int parse_bbox(const char *text, double box[4]) {
  const char *p = text;
  for (int i = 0; i < 4; i++) {
    char *end;
    errno = 0;
    box[i] = strtod(p, &end);
    if (end == p || errno || !isfinite(box[i]) || *end != (i < 3 ? ',' : '\0'))
      return cli_usage_error("site", "--bbox: '%s' is not W,S,E,N (four numbers, degrees)", text);
    p = end + 1;
  }
  if (!(box[0] >= -180 && box[2] <= 180 && box[1] >= -90 && box[3] <= 90 && box[0] < box[2] &&
        box[1] < box[3]))
    return cli_usage_error("site",
                           "--bbox: '%s': west must be below east and south below north, "
                           "longitudes within -180..180, latitudes within -90..90",
                           text);
  return CLI_PARSED;
}

/* X,Y into two fields (within the argument, which is split in place). */
static int parse_xy(char *text, site_options *o) {
  char *comma = strchr(text, ',');
  if (!comma || comma == text || !comma[1] || strchr(comma + 1, ','))
    return cli_usage_error("site", "--xy-fields: '%s' is not X,Y (two field names)", text);
  *comma = '\0';
  o->x_field = text;
  o->y_field = comma + 1;
  return CLI_PARSED;
}

typedef struct site_args {
  site_options o;
  site_scenario sc;
  const char *out;
  site_keep *keep;
} site_args;

static int parse_args(int argc, char **argv, site_args *a) {
  site_options *o = &a->o;
  *o = (site_options){.height_unit = 1.0, .level_height = 3.0, .dbh_unit = 1.0, .iterations = 10};
  a->sc = (site_scenario){.name = "site", .iterations = 10};
  if (!(a->keep = calloc((size_t)argc, sizeof *a->keep))) {
    fprintf(stderr, "sylva: out of memory\n");
    return CLI_EXIT_FAILURE;
  }
  cli_parser p;
  cli_parser_init(&p, "site", site_options_list, OPT_COUNT, argc, argv);
  const char *arg;
  int first = argc, opt, rc = CLI_PARSED;
  uint64_t v;
  while (rc == CLI_PARSED && (opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
      case OPT_BUILDINGS: o->buildings = arg; break;
      case OPT_BUILDINGS_CRS: o->buildings_crs = arg; break;
      case OPT_HEIGHT_FIELD: o->height_field = arg; break;
      case OPT_HEIGHT_UNIT:
        rc = parse_unit("height-unit", arg, "m", "ft", 0.3048, &o->height_unit);
        break;
      case OPT_LEVELS_FIELD: o->levels_field = arg; break;
      case OPT_LEVEL_HEIGHT:
        rc = parse_real("level-height", arg, 0, 100, true, "a height above 0 m, at most 100",
                        &o->level_height);
        break;
      case OPT_DEFAULT_HEIGHT:
        rc = parse_real("default-height", arg, 0, 1000, true, "a height above 0 m, at most 1000",
                        &o->default_height);
        break;
      case OPT_BUILDING_ID: o->building_id_field = arg; break;
      case OPT_TREES: o->trees = arg; break;
      case OPT_LAYER_CRS: o->trees_crs = arg; break;
      case OPT_XY_FIELDS: rc = parse_xy((char *)arg, o); break;
      case OPT_SPECIES_FIELD: o->species_field = arg; break;
      case OPT_DBH_FIELD: o->dbh_field = arg; break;
      case OPT_DBH_UNIT: rc = parse_unit("dbh-unit", arg, "cm", "in", 2.54, &o->dbh_unit); break;
      case OPT_ID_FIELD: o->id_field = arg; break;
      case OPT_KEEP: {
        const char *eq = strchr(arg, '=');
        if (!eq || eq == arg) {
          rc = cli_usage_error("site", "--keep: '%s' is not FIELD=VALUE", arg);
          break;
        }
        *(char *)eq = '\0';
        a->keep[o->keep_count++] = (site_keep){arg, eq + 1};
        break;
      }
      case OPT_SPECIES_MAP: o->species_map = arg; break;
      case OPT_DEFAULT_DBH:
        rc = parse_real("default-dbh", arg, 0, 300, true, "a DBH above 0 cm, at most 300",
                        &o->default_dbh);
        break;
      case OPT_ZONES: o->zones = arg; break;
      case OPT_ZONES_CRS: o->zones_crs = arg; break;
      case OPT_ZONE_FIELD: o->zone_field = arg; break;
      case OPT_BBOX:
        rc = parse_bbox(arg, o->bbox);
        o->has_bbox = true;
        break;
      case OPT_CRS: o->crs = arg; break;
      case OPT_REGION: o->region = arg; break;
      case OPT_NAME:
        if (!arg[0] || strlen(arg) > 255)
          rc = cli_usage_error("site", "--name: the scenario's name is 1 to 255 bytes");
        a->sc.name = arg;
        break;
      case OPT_ITERATIONS:
        if (cli_parse_u64("site", "iterations", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &v))
          return CLI_EXIT_USAGE;
        o->iterations = a->sc.iterations = (int)v;
        break;
      case OPT_START_YEAR:
        if (cli_parse_u64("site", "start-year", arg, 1, 9999, &v)) return CLI_EXIT_USAGE;
        a->sc.start_year = (int)v;
        break;
      case OPT_RHO:
        rc = parse_real("rho", arg, 0.01, 2.0, false, "a length from 0.01 to 2 m", &o->rho);
        a->sc.rho = o->rho;
        break;
      case OPT_OUT: a->out = arg; break;
      default: site_usage(stdout); return CLI_EXIT_OK;
    }
  }
  o->keep = a->keep;
  if (rc != CLI_PARSED) return rc;
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first < argc) return cli_usage_error("site", "unexpected argument '%s'", argv[first]);
  if (!o->buildings && !o->trees && !o->zones)
    return cli_usage_error("site", "nothing to read: give --buildings, --trees or --zones");
  if (!o->buildings && (o->buildings_crs || o->height_field || o->levels_field ||
                        o->default_height > 0 || o->building_id_field))
    return cli_usage_error("site", "the buildings' options need --buildings FILE");
  if (o->buildings && !o->height_field && !o->levels_field && !o->default_height)
    return cli_usage_error("site",
                           "--buildings needs --height-field, --levels-field or "
                           "--default-height");
  if (!o->trees && (o->trees_crs || o->x_field || o->species_field || o->dbh_field || o->id_field ||
                    o->keep_count || o->species_map || o->default_dbh > 0))
    return cli_usage_error("site", "the trees' options need --trees FILE");
  if (o->trees && (!o->species_field || !o->dbh_field))
    return cli_usage_error("site", "--trees needs --species-field F and --dbh-field F");
  if (!o->zones && (o->zones_crs || o->zone_field))
    return cli_usage_error("site", "the zones' options need --zones FILE");
  if (o->zones && !o->zone_field) return cli_usage_error("site", "--zones needs --zone-field F");
  if (!a->out || !a->out[0]) return cli_usage_error("site", "-o SITE.json is required");
  return CLI_PARSED;
}

/* The notes of the site, and what would keep `sylva run` from taking the scenario. */
static void warn(const site *s) {
  for (const char *n = s->notes; *n;) {
    size_t len = strcspn(n, "\n");
    fprintf(stderr, "sylva: note: %.*s\n", (int)len, n);
    n += len + (n[len] == '\n');
  }
  double voxels = 1;
  for (int a = 0; a < 3; a++)
    voxels *= ceil((double)(s->world_max[a] - s->world_min[a]) / s->voxel);
  if (voxels > SYLVA_MAX_VOXELS)
    fprintf(stderr,
            "sylva: warning: the world spans %.2g voxels of %g m, more than the %.2g a scenario "
            "may hold: cut the site with --bbox, or give --rho\n",
            voxels, s->voxel, SYLVA_MAX_VOXELS);
  if (s->obstacle_count > SYLVA_SCENARIO_MAX_OBSTACLES)
    fprintf(stderr,
            "sylva: warning: %d obstacles, more than the %d a scenario may hold: cut the "
            "site with --bbox\n",
            s->obstacle_count, SYLVA_SCENARIO_MAX_OBSTACLES);
}

int cmd_site(int argc, char **argv) {
  site_args a = {0};
  int rc = parse_args(argc, argv, &a);
  if (rc != CLI_PARSED) {
    free(a.keep);
    return rc;
  }
  cli_outfile out;
  if ((rc = cli_outfile_open(&out, "-o", a.out, false))) {
    free(a.keep);
    return rc;
  }
  site s;
  char err[2048];
  rc = site_build(&a.o, &s, err, sizeof err);
  free(a.keep);
  if (rc) {
    fprintf(stderr, "sylva: %s\n", err);
    return cli_outfile_close(&out, server_exit_status(rc));
  }
  warn(&s);
  char *text = site_scenario_json(&s, &a.sc), *line = text ? site_summary_json(&s) : NULL;
  site_free(&s);
  if (!line) {
    fprintf(stderr, "sylva: out of memory\n");
    free(text);
    return cli_outfile_close(&out, CLI_EXIT_FAILURE);
  }
  fputs(text, out.f);
  free(text);
  rc = cli_outfile_close(&out, CLI_EXIT_OK);
  if (rc == CLI_EXIT_OK) {
    printf("%s\n", line);
    if (fflush(stdout) != 0) rc = CLI_EXIT_FAILURE;
  }
  free(line);
  return rc;
}
