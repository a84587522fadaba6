/* `sylva export`: a stored iteration as a skeleton (JSON), a mesh (OBJ, PLY), a
 * scene with leaves (binary glTF), or the stats of every iteration (CSV). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "cli_store.h"
#include "export.h"
#include "options.h"
#include "outfile.h"
#include "sylva/scenario.h"

enum { OPT_DB, OPT_NAME, OPT_ITERATION, OPT_FORMAT, OPT_OUT, OPT_SIDES, OPT_OBSTACLES, OPT_HELP,
       OPT_COUNT };

static const cli_option export_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (required)"},
    [OPT_NAME] = {"name", 0, "NAME", "the run (required)"},
    [OPT_ITERATION] = {"iteration", 0, "T", "the stored iteration (default: the last)"},
    [OPT_FORMAT] = {"format", 0, "F", "skeleton, obj, ply, csv or glb (required)"},
    [OPT_OUT] = {"output", 'o', "OUT", "the file to write, '-' for stdout (required)"},
    [OPT_SIDES] = {"sides", 0, "N",
                   "obj, ply, glb: sides of each branch cylinder (3 to 64, default 8)"},
    [OPT_OBSTACLES] = {"obstacles", 0, NULL, "obj, ply, glb: include the obstacles as boxes"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void export_usage(FILE *f) {
  fputs("Usage: sylva export --db FILE --name NAME [--iteration T] --format F -o OUT\n"
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
        "            co2_sequestered,canopy_cover (empty where a measure is null or\n"
        "            the run has none)\n"
        "  glb       binary glTF 2.0: per stem a node <plant>/<stem> with its bark\n"
        "            (material bark) and its leaf cards (material leaves, textured);\n"
        "            metres, y up; obstacles on request\n"
        "An iteration between two snapshots is regrown from the earlier one.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, export_options, OPT_COUNT);
}

int cmd_export(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "export", export_options, OPT_COUNT, argc, argv);
  const char *db = NULL, *name = NULL, *out = NULL, *arg;
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
      if (!export_format_parse(arg, &spec.format))
        return cli_usage_error("export", "--format: '%s' is not " EXPORT_FORMAT_NAMES, arg);
      has_format = true;
      break;
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
