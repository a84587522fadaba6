/* `sylva render`: a stored iteration, or a scenario grown to its end, drawn as
 * front, side and top views, with or without leaves, into a PNG, SVG or PDF file
 * (render.h). */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include "commands.h"
#include "cli_store.h"
#include "cli_input.h"
#include "grow.h"
#include "options.h"
#include "outfile.h"
#include "render.h"
#include "sylva/scenario.h"

enum { OPT_DB, OPT_NAME, OPT_ITERATION, OPT_SEED, OPT_ITERATIONS, OPT_THREADS, OPT_VIEW,
       OPT_WIDTH, OPT_NO_LEAVES, OPT_OUT, OPT_HELP, OPT_COUNT };

static const cli_option render_cli_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store holding the run"},
    [OPT_NAME] = {"name", 0, "NAME", "the stored run"},
    [OPT_ITERATION] = {"iteration", 0, "T", "the stored iteration (default: the last)"},
    [OPT_SEED] = {"seed", 0, "N", "SCENARIO: override its seed (0 to 2^53)"},
    [OPT_ITERATIONS] = {"iterations", 0, "N", "SCENARIO: override its limit (1 to 100000)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "threads the world grows on (1 to 256, default: the cores)"},
    [OPT_VIEW] = {"view", 0, "V", "front, side, top or all (default all)"},
    [OPT_WIDTH] = {"width", 0, "PX", "picture width, 400 to 16384 (default 500 per view)"},
    [OPT_NO_LEAVES] = {"no-leaves", 0, NULL, "draw the branches only, without the leaves"},
    [OPT_OUT] = {"output", 'o', "OUT", "the file to write: OUT.png, OUT.svg or OUT.pdf (required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void render_usage(FILE *f) {
  fputs("Usage: sylva render --db FILE --name NAME [--iteration T] [--view V] [--width PX]\n"
        "                    [--no-leaves] -o OUT\n"
        "       sylva render SCENARIO.json [--seed N] [--iterations N] [--view V] [--width PX]\n"
        "                    [--no-leaves] -o OUT\n"
        "\n"
        "Draws a stored iteration of a run, or a scenario grown until every stem has\n"
        "finished or its iteration limit, as orthographic views of the world's box:\n"
        "  front  x-z, looking along +y (x to the right)\n"
        "  side   y-z, looking along -x (y to the right)\n"
        "  top    x-y, seen from above (x to the right, y up)\n"
        "  all    the three side by side (the default)\n"
        "Internodes are lines as wide as their diameter (at least half a pixel), one\n"
        "colour per plant. Over them every leaf is an ellipse (at least a pixel) in\n"
        "its species' leaf_colour, darker the more it is seen edge-on; --no-leaves\n"
        "draws the branches only. Obstacles are translucent grey boxes; front and side\n"
        "show the ground. Each view has scales in metres (equal on both axes), and a\n"
        "title line names the run, the iteration and the live nodes.\n"
        "The format follows OUT's extension: .png, .svg or .pdf (SVG and PDF are\n"
        "vector pictures, one point per pixel). OUT is written to OUT.tmp, then renamed.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, render_cli_options, OPT_COUNT);
}

/* What the command line asked for. */
typedef struct render_args {
  const char *db, *name, *scenario, *seed_text, *out;
  uint64_t iteration, seed, iterations;
  bool has_iteration;
  int threads;
  render_options ro;
} render_args;

/* Parses argv into a; returns CLI_PARSED to go on, or the exit status to end with. */
static int parse_args(int argc, char **argv, render_args *a) {
  cli_parser p;
  cli_parser_init(&p, "render", render_cli_options, OPT_COUNT, argc, argv);
  uint64_t width = 0;
  const char *arg;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: a->db = arg; break;
    case OPT_NAME: a->name = arg; break;
    case OPT_ITERATION:
      if (cli_parse_u64("render", "iteration", arg, 0, SYLVA_SCENARIO_MAX_ITERATIONS,
                        &a->iteration))
        return CLI_EXIT_USAGE;
      a->has_iteration = true;
      break;
    case OPT_SEED:
      if (cli_parse_u64("render", "seed", arg, 0, (uint64_t)SYLVA_SCENARIO_SEED_MAX, &a->seed))
        return CLI_EXIT_USAGE;
      a->seed_text = arg;
      break;
    case OPT_ITERATIONS:
      if (cli_parse_u64("render", "iterations", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS,
                        &a->iterations))
        return CLI_EXIT_USAGE;
      break;
    case OPT_THREADS:
      if (cli_parse_threads("render", arg, &a->threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_VIEW:
      if (!render_view_parse(arg, &a->ro.view))
        return cli_usage_error("render", "--view: expected " RENDER_VIEW_NAMES ", got '%s'", arg);
      break;
    case OPT_WIDTH:
      if (cli_parse_u64("render", "width", arg, RENDER_MIN_WIDTH, RENDER_MAX_SIZE, &width))
        return CLI_EXIT_USAGE;
      a->ro.width = (int)width;
      break;
    case OPT_NO_LEAVES: a->ro.no_leaves = true; break;
    case OPT_OUT: a->out = arg; break;
    default:
      render_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (argc - first > 1)
    return cli_usage_error("render", "unexpected argument '%s'", argv[first + 1]);
  if (argc - first == 1) a->scenario = argv[first];
  if (a->scenario && (a->db || a->name || a->has_iteration))
    return cli_usage_error("render", "--db, --name and --iteration are for a stored run, not "
                                     "for SCENARIO.json");
  if (!a->scenario && (a->seed_text || a->iterations))
    return cli_usage_error("render", "--seed and --iterations need SCENARIO.json");
  if (!a->scenario && !a->db && !a->name)
    return cli_usage_error("render", "expected --db FILE --name NAME, or SCENARIO.json");
  if (!a->out || !a->out[0]) return cli_usage_error("render", "-o OUT is required");
  if (!render_format_from_path(a->out, &a->ro.format))
    return cli_usage_error("render", "-o: '%s' does not end in " RENDER_FORMAT_NAMES, a->out);
  return CLI_PARSED;
}

/* Draws w into the already opened output. */
static int render_to(cli_outfile *o, const sylva_world *w, const render_options *ro) {
  char err[512];
  int failed = render_write(o->f, w, ro, err, sizeof err);
  if (failed == SERVER_EWRITE)
    fprintf(stderr, "sylva: %s: %s\n", o->path, err);
  else if (failed)
    fprintf(stderr, "sylva: render: %s\n", err);
  return server_exit_status(failed);
}

/* The stored form: --db FILE --name NAME [--iteration T]. */
static int render_stored(render_args *a) {
  store *st;
  store_run r;
  int rc = cli_open_run("render", a->db, a->name, &st, &r);
  if (rc) return rc;
  int at = 0;
  rc = cli_stored_iteration(a->db, &r, a->has_iteration, a->iteration, &at);
  cli_outfile o = {0};
  if (rc == CLI_EXIT_OK) rc = cli_outfile_open(&o, "-o", a->out, false);
  sylva_world *w = NULL;
  store_set_threads(st, a->threads); /* its regrowing from the snapshot before it */
  if (rc == CLI_EXIT_OK) rc = cli_store_world_at(st, &r, at, &w);
  a->ro.name = r.name;
  a->ro.start_year = r.start_year;
  if (rc == CLI_EXIT_OK) rc = render_to(&o, w, &a->ro);
  rc = cli_outfile_close(&o, rc);
  if (w) sylva_world_destroy(w);
  store_run_free(&r);
  store_close(st);
  return rc;
}

/* The scenario form: SCENARIO.json grown silently to its end. */
static int render_scenario(render_args *a) {
  sylva_scenario *s;
  int rc = cli_input_scenario(a->scenario, SYLVA_SCENARIO_NEED_PLANTS, &s);
  if (rc) return rc;
  if (a->seed_text) s->seed = a->seed;
  /* open the output now, so that a bad path fails before the growing */
  cli_outfile o = {0};
  rc = cli_outfile_open(&o, "-o", a->out, false);
  sylva_world *w = NULL;
  if (rc == CLI_EXIT_OK) rc = cli_input_world(a->scenario, s, &w);
  grow_job job = {.label = a->scenario, .w = w, .threads = a->threads,
                  .limit = a->iterations ? (int)a->iterations : s->iterations,
                  .progress = isatty(STDERR_FILENO), .silent = true};
  if (rc == CLI_EXIT_OK) rc = grow_run(&job);
  a->ro.name = s->name;
  a->ro.start_year = s->start_year;
  if (rc == CLI_EXIT_OK) rc = render_to(&o, w, &a->ro);
  rc = cli_outfile_close(&o, rc);
  if (w) sylva_world_destroy(w);
  sylva_scenario_free(s);
  return rc;
}

int cmd_render(int argc, char **argv) {
  render_args a = {.threads = cli_default_threads(1),
                   .ro = {.format = RENDER_PNG, .view = RENDER_ALL, .width = 0, .name = NULL}};
  int rc = parse_args(argc, argv, &a);
  if (rc != CLI_PARSED) return rc;
  rc = a.scenario ? render_scenario(&a) : render_stored(&a);
  /* cairo's font caches and fontconfig's hold memory until the process ends;
   * free them so that leak checkers see none */
  cairo_debug_reset_static_data();
  FcFini();
  return rc;
}
