/* `sylva report`: the planner's comparison of a sweep's runs (or of the runs of a store
 * without sweeps) at chosen years, as CSV, HTML or PDF (report.h, docs/cli.md
 * "report"). Everything is checked before the output is created, so bad input leaves
 * no file behind. */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include "cli_store.h"
#include "commands.h"
#include "options.h"
#include "outfile.h"
#include "render.h"
#include "report.h"

enum { OPT_DB, OPT_SWEEP, OPT_YEARS, OPT_VIEW, OPT_WIDTH, OPT_OUT, OPT_HELP, OPT_COUNT };

static const cli_option report_cli_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (required; it must exist)"},
    [OPT_SWEEP] = {"sweep", 0, "NAME", "the sweep to report (default: the store's only one)"},
    [OPT_YEARS] = {"years", 0, "LIST", "years since planting, e.g. 10,20,40 (the default)"},
    [OPT_VIEW] = {"view", 0, "V", "HTML, PDF: the pictures' view, front, side, top or all "
                                  "(default front)"},
    [OPT_WIDTH] = {"width", 0, "PX", "HTML, PDF: the pictures' width, 400 to 16384 (default 500 "
                                     "per view)"},
    [OPT_OUT] = {"output", 'o', "OUT", "the file to write: OUT.csv, OUT.html or OUT.pdf "
                                       "(required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void report_usage(FILE *f) {
  fputs("Usage: sylva report --db FILE [--sweep NAME] [--years LIST] [--view V] [--width PX]\n"
        "                    -o OUT.csv|OUT.html|OUT.pdf\n"
        "\n"
        "Compares the runs of a sweep (`sylva sweep`) at the given years since planting\n"
        "(the stats of iteration = year; a run that has not reached a year has no row\n"
        "for it). Without --sweep, the store's only sweep is reported, or, in a store\n"
        "without sweeps, every run of it.\n"
        "  .csv   one row per run, plant and year: the run, its axes, the plant, its\n"
        "         species and age, the year, height, dbh, crown diameter and height, the\n"
        "         first conflict year with each clearance zone, the least clearance to\n"
        "         each solid obstacle and the nodes pruned so far; the stem's CO2 stored\n"
        "         and sequestered, the run's canopy cover, and, when the sweep's plan\n"
        "         names a \"shade\" day, the run's tree shade hours on the ground and on\n"
        "         each solid obstacle\n"
        "  .html  one self-contained page: the summary (per axis value, seeds pooled:\n"
        "  .pdf   median and range), each species drawn at each year, plots of height\n"
        "         and crown diameter over the years (the Urban Tree Database's open-grown\n"
        "         curves dashed) and the first conflicts per species and zone\n"
        "OUT is written to OUT.tmp, then renamed.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, report_cli_options, OPT_COUNT);
}

/* What the command line asked for. */
typedef struct report_args {
  const char *db, *sweep, *out;
  int years[REPORT_MAX_YEARS], nyears;
  report_format format;
  report_draw_options draw;
} report_args;

/* Parses argv into a; returns CLI_PARSED to go on, or the exit status to end with. */
static int parse_args(int argc, char **argv, report_args *a) {
  cli_parser p;
  cli_parser_init(&p, "report", report_cli_options, OPT_COUNT, argc, argv);
  const char *years = REPORT_DEFAULT_YEARS, *arg;
  uint64_t width = 0;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: a->db = arg; break;
    case OPT_SWEEP: a->sweep = arg; break;
    case OPT_YEARS: years = arg; break;
    case OPT_VIEW:
      if (!render_view_parse(arg, &a->draw.view))
        return cli_usage_error("report", "--view: expected " RENDER_VIEW_NAMES ", got '%s'", arg);
      break;
    case OPT_WIDTH:
      if (cli_parse_u64("report", "width", arg, RENDER_MIN_WIDTH, RENDER_MAX_SIZE, &width))
        return CLI_EXIT_USAGE;
      a->draw.width = (int)width;
      break;
    case OPT_OUT: a->out = arg; break;
    default:
      report_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("report", "unexpected argument '%s'", argv[first]);
  if (!a->db || !a->db[0]) return cli_usage_error("report", "--db FILE is required");
  if (a->sweep && !a->sweep[0]) return cli_usage_error("report", "--sweep: an empty name");
  char err[256];
  if (!report_parse_years(years, a->years, &a->nyears, err, sizeof err))
    return cli_usage_error("report", "--years: %s", err);
  if (!a->out || !a->out[0]) return cli_usage_error("report", "-o OUT is required");
  if (!report_format_from_path(a->out, &a->format))
    return cli_usage_error("report", "-o: '%s' does not end in " REPORT_FORMAT_NAMES, a->out);
  return CLI_PARSED;
}

/* Writes r to the opened output in the format asked for. */
static int write_report(cli_outfile *o, store *st, const report *r, const report_args *a) {
  char err[512] = "";
  int failed;
  switch (a->format) {
  case REPORT_CSV: failed = report_write_csv(o->f, r, err, sizeof err); break;
  case REPORT_HTML: failed = report_write_html(o->f, st, r, &a->draw, err, sizeof err); break;
  default: failed = report_write_pdf(o->f, st, r, &a->draw, err, sizeof err); break;
  }
  if (failed == SERVER_EWRITE)
    fprintf(stderr, "sylva: %s: %s\n", o->path, err);
  else if (failed)
    fprintf(stderr, "sylva: report: %s\n", err);
  return server_exit_status(failed);
}

/* A run that reached none of the years gives no rows: say so, it is not an error. */
static void warn_empty(const report *r) {
  if (r->nrows) return;
  fprintf(stderr, "sylva: warning: %s: no run has reached any of the reported years (",
          r->db);
  for (int i = 0; i < r->nyears; i++) fprintf(stderr, "%s%d", i ? ", " : "", r->years[i]);
  fprintf(stderr, "); the longest has %d iteration%s\n", r->max_iteration,
          r->max_iteration == 1 ? "" : "s");
}

static int run_report(report_args *a) {
  store *st;
  int rc = cli_store_open(a->db, false, &st);
  if (rc) return rc;
  report_request q = {.db = a->db, .sweep = a->sweep, .years = a->years, .nyears = a->nyears,
                      .warn = a->draw.warn};
  report *r = NULL;
  char err[1024];
  int failed = report_load(st, &q, &r, err, sizeof err);
  if (failed) {
    fprintf(stderr, "sylva: %s\n", err);
    store_close(st);
    return server_exit_status(failed);
  }
  warn_empty(r);
  cli_outfile o = {0};
  rc = cli_outfile_open(&o, "-o", a->out, false);
  if (rc == CLI_EXIT_OK) rc = write_report(&o, st, r, a);
  rc = cli_outfile_close(&o, rc);
  report_free(r);
  store_close(st);
  return rc;
}

int cmd_report(int argc, char **argv) {
  report_args a = {.draw = {.view = RENDER_FRONT, .width = 0, .warn = cli_store_warn}};
  int rc = parse_args(argc, argv, &a);
  if (rc != CLI_PARSED) return rc;
  rc = run_report(&a);
  /* cairo's font caches and fontconfig's hold memory until the process ends; free
   * them so that leak checkers see none */
  cairo_debug_reset_static_data();
  FcFini();
  return rc;
}
