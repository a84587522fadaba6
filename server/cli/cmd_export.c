/* `sylva export`: a stored iteration as a skeleton (JSON), a mesh (OBJ, PLY), a
 * scene with leaves (binary glTF), or the stats of every iteration (CSV). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "cli_store.h"
#include "export.h"
#include "gis_export.h"
#include "options.h"
#include "outfile.h"
#include "report.h"
#include "sylva/scenario.h"

enum { OPT_DB, OPT_NAME, OPT_ITERATION, OPT_YEARS, OPT_FORMAT, OPT_OUT, OPT_SIDES, OPT_OBSTACLES,
       OPT_HELP, OPT_COUNT };

static const cli_option export_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (required)"},
    [OPT_NAME] = {"name", 0, "NAME", "the run (required)"},
    [OPT_ITERATION] = {"iteration", 0, "T", "the stored iteration (default: the last)"},
    [OPT_YEARS] = {"years", 0, "LIST",
                   "geojson, gpkg: years since planting, e.g. 10,20 (default: the last stored)"},
    [OPT_FORMAT] = {"format", 0, "F", "skeleton, obj, ply, csv, glb, geojson or gpkg (required)"},
    [OPT_OUT] = {"output", 'o', "OUT", "the file to write, '-' for stdout (required)"},
    [OPT_SIDES] = {"sides", 0, "N",
                   "obj, ply, glb: sides of each branch cylinder (3 to 64, default 8)"},
    [OPT_OBSTACLES] = {"obstacles", 0, NULL, "obj, ply, glb: include the obstacles as boxes"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void export_usage(FILE *f) {
  fputs("Usage: sylva export --db FILE --name NAME [--iteration T | --years LIST] --format F -o OUT\n"
        "\n"
        "Writes a stored iteration of a run:\n"
        "  skeleton  sylva.skeleton/1 JSON: every node [id, parent, x, y, z, radius, birth]\n"
        "  obj, ply  a mesh of the branches: tapered generalized cylinders with radii\n"
        "            from the model, one object per stem (OBJ), obstacles on request\n"
        "  csv       the stats of every stored iteration up to T, one row per stem:\n"
        "            iteration,plant,stem,height,dbh,crown_width,crown_base,nodes,shed,\n"
        "            light,cap,finished,pruned,zones,clearance,leaf_area, in a run in\n"
        "            years or from a start year age,year,crown_diameter,crown_height,\n"
        "            then crown_area,wood_volume,biomass,biomass_model,carbon,co2,\n"
        "            co2_sequestered,canopy_cover, in a run with stands alive,died,\n"
        "            vigour,stems_per_ha,basal_area,qmd,dominant_height,sdi,cv_height,\n"
        "            cv_dbh,stand_died (empty where a measure is null or the run has\n"
        "            none)\n"
        "  glb       binary glTF 2.0: per stem a node <plant>/<stem> with its bark\n"
        "            (material bark) and its leaf cards (material leaves, textured);\n"
        "            metres, y up; obstacles on request\n"
        "  geojson   for a run with a site (`sylva site`), at each of --years: every\n"
        "            stem's trunk (a point) and crown (the ground under its leaves, a\n"
        "            polygon) with its figures and zones' conflict years; the\n"
        "            buildings and zones of the last year; one RFC 7946 collection in\n"
        "            WGS 84, each feature's `layer` trunks, crowns, buildings or zones\n"
        "  gpkg      the same as a GeoPackage of those four layers, in the site's CRS\n"
        "An iteration between two snapshots is regrown from the earlier one.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, export_options, OPT_COUNT);
}

/* geojson, gpkg: GDAL writes OUT.tmp (it needs a path), renamed over OUT at the end. */
static int export_gis(const char *db, const char *name, const char *years_text, bool gpkg,
                      const char *out) {
  int years[REPORT_MAX_YEARS], nyears = 0;
  char err[512];
  if (years_text && !report_parse_years(years_text, years, &nyears, err, sizeof err))
    return cli_usage_error("export", "--years: %s", err);
  store *st;
  store_run r;
  int rc = cli_open_run("export", db, name, &st, &r);
  if (rc) return rc;
  if (!years_text) years[nyears++] = r.last_iteration;
  if (years[nyears - 1] > r.last_iteration || years[0] < 1) {
    fprintf(stderr, "sylva export: --years: run \"%s\" has stored years 1 to %d, not %d\n", r.name,
            r.last_iteration, years[0] < 1 ? years[0] : years[nyears - 1]);
    rc = CLI_EXIT_USAGE;
  }
  bool to_stdout = strcmp(out, "-") == 0;
  size_t n = strlen(out) + 5;
  char *tmp = to_stdout ? NULL : malloc(n);
  if (!rc && !to_stdout && !tmp) rc = CLI_EXIT_FAILURE;
  if (!rc && tmp) {
    snprintf(tmp, n, "%s.tmp", out);
    if (remove(tmp) != 0 && errno != ENOENT) {
      fprintf(stderr, "sylva: -o: cannot replace %s: %s\n", tmp, strerror(errno));
      rc = CLI_EXIT_USAGE;
    }
  }
  if (!rc) {
    gis_export_spec spec = {.run = r.id, .name = r.name, .scenario = r.scenario,
                            .start_year = r.start_year, .years = years,
                            .year_count = (size_t)nyears, .gpkg = gpkg,
                            .path = to_stdout ? "/vsistdout/" : tmp};
    int failed = gis_export_write(st, &spec, cli_store_warn, err, sizeof err);
    if (failed) fprintf(stderr, "sylva: %s\n", err);
    rc = server_exit_status(failed);
    if (tmp && !rc && rename(tmp, out) != 0) {
      fprintf(stderr, "sylva: %s: %s\n", out, strerror(errno));
      rc = CLI_EXIT_FAILURE;
    }
    if (tmp && rc) remove(tmp);
  }
  free(tmp);
  store_run_free(&r);
  store_close(st);
  return rc;
}

int cmd_export(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "export", export_options, OPT_COUNT, argc, argv);
  const char *db = NULL, *name = NULL, *out = NULL, *years_text = NULL, *arg;
  enum { GIS_GEOJSON = 1, GIS_GPKG } gis = 0;
  uint64_t iteration = 0, sides = 8;
  bool has_iteration = false, has_format = false;
  export_spec spec = {0};
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: db = arg; break;
    case OPT_NAME: name = arg; break;
    case OPT_ITERATION:
      if (cli_parse_u64("export", "iteration", arg, 0, SYLVA_SCENARIO_MAX_ITERATIONS, &iteration))
        return CLI_EXIT_USAGE;
      has_iteration = true;
      break;
    case OPT_FORMAT:
      gis = strcmp(arg, "geojson") == 0 ? GIS_GEOJSON : strcmp(arg, "gpkg") == 0 ? GIS_GPKG : 0;
      if (!gis && !export_format_parse(arg, &spec.format))
        return cli_usage_error("export", "--format: '%s' is not " EXPORT_FORMAT_NAMES
                               ", geojson or gpkg", arg);
      has_format = true;
      break;
    case OPT_YEARS: years_text = arg; break;
    case OPT_OUT: out = arg; break;
    case OPT_SIDES:
      if (cli_parse_u64("export", "sides", arg, 3, 64, &sides)) return CLI_EXIT_USAGE;
      break;
    case OPT_OBSTACLES: spec.obstacles = true; break;
    default:
      export_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("export", "unexpected argument '%s'", argv[first]);
  if (!has_format) return cli_usage_error("export", "--format is required");
  if (!out || !out[0]) return cli_usage_error("export", "-o OUT is required");
  if (gis) {
    if (has_iteration) return cli_usage_error("export", "--iteration: geojson and gpkg take --years");
    if (gis == GIS_GPKG && strcmp(out, "-") == 0)
      return cli_usage_error("export", "-o: a GeoPackage cannot go to stdout; name a file");
    return export_gis(db, name, years_text, gis == GIS_GPKG, out);
  }
  if (years_text) return cli_usage_error("export", "--years: only geojson and gpkg take it");

  store *st;
  store_run r;
  int rc = cli_open_run("export", db, name, &st, &r);
  if (rc) return rc;
  int at = 0;
  rc = cli_stored_iteration(db, &r, has_iteration, iteration, &at);
  spec.run = r.id;
  spec.name = r.name;
  spec.iteration = at;
  spec.sides = (int)sides;

  /* write to OUT.tmp and rename, so that OUT is never half written */
  cli_outfile o;
  if (rc == CLI_EXIT_OK) rc = cli_outfile_open(&o, "-o", out, true);
  if (rc == CLI_EXIT_OK) {
    char err[512];
    int failed = export_write(o.f, st, &spec, cli_store_warn, err, sizeof err);
    if (failed == SERVER_EWRITE)
      fprintf(stderr, "sylva: %s: %s\n", out, err);
    else if (failed)
      fprintf(stderr, "sylva: %s\n", err);
    rc = cli_outfile_close(&o, server_exit_status(failed));
  }
  store_run_free(&r);
  store_close(st);
  return rc;
}
