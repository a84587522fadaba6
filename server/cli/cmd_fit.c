/* `sylva fit`: calibrates a species in years to the Urban Tree Database or to a
 * user's measured trees (docs/cli.md, "fit"; docs/model.md, "Calibration"). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "files.h"
#include "fit.h"
#include "fit_report.h"
#include "options.h"
#include "outfile.h"
#include "sylva/scenario.h"
#include "utdb.h"

enum { OPT_UTDB, OPT_OUT, OPT_REPORT, OPT_SEEDS, OPT_EVALS, OPT_RHO, OPT_THREADS, OPT_HELP, OPT_COUNT };

static const cli_option fit_options[OPT_COUNT] = {
    [OPT_UTDB] = {"utdb", 0, "REGION:CODE", "calibrate to the Urban Tree Database's curves"},
    [OPT_OUT] = {"output", 'o', "FILE", "the species object (JSON) to write (required)"},
    [OPT_REPORT] = {"report", 0, "PREFIX", "write PREFIX.md and PREFIX.png (default: FILE less .json)"},
    [OPT_SEEDS] = {"seeds", 0, "N", "trees grown per evaluation, medians taken (1-16, default 3)"},
    [OPT_EVALS] = {"evals", 0, "N", "evaluations of the search (1-1000, default 40)"},
    [OPT_RHO] = {"rho", 0, "M", "internode length in m (0.05-2; default 0.25, halved for slow growth)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "trees grown at once, one thread each (1 to 256, default: the cores)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void fit_usage(FILE *f) {
  fputs("Usage: sylva fit (DATA.csv | --utdb REGION:CODE) -o SPECIES.json [OPTIONS]\n"
        "\n"
        "Calibrates a species in years, one iteration a growing season, to measured\n"
        "growth: the Urban Tree Database's curves of a species and region (McPherson,\n"
        "van Doorn and Peper 2016, https://doi.org/10.2737/RDS-2016-0005), or a CSV of\n"
        "your own trees with the header age,dbh_cm,height_m,crown_diameter_m,crown_height_m\n"
        "(one row per tree; every value but age may be empty). It fits the growth curves\n"
        "(GSL nonlinear least squares), then searches the crown's spread and the\n"
        "height's scale with the simulation in the loop (GSL's simplex, median of the\n"
        "seeds), then the trunk's tip radius and pipe exponent.\n"
        "\n"
        "SPECIES.json holds one species object: use it as a scenario's species,\n"
        "\"species\": {\"mine\": <the object>}. The report is a table of the model against\n"
        "the data at each decade (PREFIX.md) and a picture of the curves (PREFIX.png).\n"
        "Progress goes to stderr; stdout gets one JSON line with the largest errors.\n"
        "Bad data exits 2 and writes nothing.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, fit_options, OPT_COUNT);
}

static void on_progress(void *ctx, const char *line) {
  (void)ctx;
  fprintf(stderr, "%s\n", line);
}

static double seconds_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Finds REGION:CODE, or prints what is known and returns CLI_EXIT_USAGE. */
static int find_utdb(const sylva_utdb *u, const char *key, const sylva_utdb_species **out) {
  const char *colon = strchr(key, ':');
  char region[32] = "";
  if (colon && (size_t)(colon - key) < sizeof region) memcpy(region, key, (size_t)(colon - key));
  if (!colon || !region[0] || !colon[1])
    return cli_usage_error("fit", "--utdb: '%s' is not REGION:CODE (for example NoEast:PLAC)", key);
  *out = sylva_utdb_find(u, region, colon + 1);
  if (*out) return CLI_EXIT_OK;
  char known[2048] = "";
  size_t n = 0;
  bool region_known = false;
  for (int i = 0; i < sylva_utdb_count(u); i++)
    if (strcmp(sylva_utdb_at(u, i)->region, region) == 0) region_known = true;
  for (int i = 0; i < sylva_utdb_count(u) && n + 40 < sizeof known; i++) {
    const sylva_utdb_species *s = sylva_utdb_at(u, i);
    if (region_known ? strcmp(s->region, region) == 0
                     : (i == 0 || strcmp(s->region, sylva_utdb_at(u, i - 1)->region) != 0))
      n += (size_t)snprintf(known + n, sizeof known - n, "%s%s", n ? ", " : "",
                            region_known ? s->code : s->region);
  }
  if (region_known)
    return cli_usage_error("fit", "--utdb: no species %s in region %s of the Urban Tree Database "
                           "(its codes: %s)", colon + 1, region, known);
  return cli_usage_error("fit", "--utdb: no region %s in the Urban Tree Database (regions: %s)",
                         region, known);
}

int cmd_fit(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "fit", fit_options, OPT_COUNT, argc, argv);
  const char *utdb_key = NULL, *out_path = NULL, *report = NULL, *arg;
  sylva_fit_options o = sylva_fit_default_options();
  o.progress = on_progress;
  o.threads = cli_default_threads(1);
  int first = argc, opt;
  uint64_t v;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_UTDB: utdb_key = arg; break;
    case OPT_OUT: out_path = arg; break;
    case OPT_REPORT: report = arg; break;
    case OPT_SEEDS:
      if (cli_parse_u64("fit", "seeds", arg, 1, 16, &v)) return CLI_EXIT_USAGE;
      o.seeds = (int)v;
      break;
    case OPT_EVALS:
      if (cli_parse_u64("fit", "evals", arg, 1, 1000, &v)) return CLI_EXIT_USAGE;
      o.max_evals = (int)v;
      break;
    case OPT_THREADS:
      if (cli_parse_threads("fit", arg, &o.threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_RHO: {
      char *end;
      errno = 0;
      double r = strtod(arg, &end);
      if (end == arg || *end || errno || !(r >= 0.05 && r <= 2.0))
        return cli_usage_error("fit", "--rho: '%s' is not a length from 0.05 to 2 m", arg);
      o.rho = r;
      break;
    }
    default: fit_usage(stdout); return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  const char *data_path = first < argc ? argv[first] : NULL;
  if (first + 1 < argc) return cli_usage_error("fit", "unexpected argument '%s'", argv[first + 1]);
  if (!data_path == !utdb_key)
    return cli_usage_error("fit", "give either DATA.csv or --utdb REGION:CODE");
  if (!out_path || !out_path[0]) return cli_usage_error("fit", "-o FILE is required");

  sylva_fit_targets targets;
  sylva_fit_tree *trees = NULL;
  int count = 0;
  char title[512], err[512] = "";
  if (utdb_key) {
    sylva_utdb *u = NULL;
    if (sylva_utdb_builtin(&u)) {
      fprintf(stderr, "sylva fit: the built-in Urban Tree Database could not be read\n");
      return CLI_EXIT_FAILURE;
    }
    const sylva_utdb_species *s = NULL;
    int rc = find_utdb(u, utdb_key, &s);
    if (!rc && sylva_fit_targets_utdb(s, &targets, err, sizeof err)) {
      fprintf(stderr, "sylva fit: --utdb: %s\n", err);
      rc = CLI_EXIT_USAGE;
    }
    if (!rc)
      snprintf(title, sizeof title, "%s:%s %s (%s), Urban Tree Database, n %d, R2 height %.2f",
               s->region, s->code, s->scientific, s->common, s->curve[SYLVA_UTDB_HEIGHT].n,
               s->curve[SYLVA_UTDB_HEIGHT].r2);
    sylva_utdb_free(u);
    if (rc) return rc;
  } else {
    char *text = NULL;
    size_t len = 0;
    if (files_read(data_path, (size_t)64 << 20, &text, &len)) {
      fprintf(stderr, "sylva fit: %s: %s\n", data_path, strerror(errno));
      return CLI_EXIT_USAGE;
    }
    int rc = sylva_fit_read_csv(text, len, &trees, &count, err, sizeof err);
    free(text);
    sylva_fit_curve curves[4];
    if (!rc) rc = sylva_fit_targets_trees(trees, count, &targets, curves, err, sizeof err);
    if (rc) {
      fprintf(stderr, "sylva fit: %s: %s\n", data_path, err);
      free(trees);
      return rc == SYLVA_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
    }
    snprintf(title, sizeof title, "%s: %d trees, height curve R2 %.2f", data_path, count,
             curves[0].r2);
  }
  double t0 = seconds_now();
  sylva_fit_result r;
  int rc = sylva_fit_calibrate(&targets, &o, &r, err, sizeof err);
  if (rc) {
    fprintf(stderr, "sylva fit: %s\n", err);
    free(trees);
    return rc == SYLVA_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
  }
  double secs = seconds_now() - t0;
  char *json = sylva_species_json(&r.def);
  cli_outfile of;
  rc = json ? cli_outfile_open(&of, "-o", out_path, false) : CLI_EXIT_FAILURE;
  if (!rc) {
    fputs(json, of.f);
    fputc('\n', of.f);
    rc = cli_outfile_close(&of, CLI_EXIT_OK);
  }
  free(json);
  /* the report beside it */
  char prefix[1024];
  if (!rc) {
    size_t n = strlen(out_path);
    if (report)
      snprintf(prefix, sizeof prefix, "%s", report);
    else if (n > 5 && strcmp(out_path + n - 5, ".json") == 0)
      snprintf(prefix, sizeof prefix, "%.*s", (int)(n - 5), out_path);
    else
      snprintf(prefix, sizeof prefix, "%s", out_path);
    char md[1100], png[1100];
    snprintf(md, sizeof md, "%s.md", prefix);
    snprintf(png, sizeof png, "%s.png", prefix);
    if (!rc && cli_outfile_open(&of, "--report", md, false) == 0) {
      fprintf(of.f, "# %s\n\nThe model (median of %d seeds) against the data at each decade:\n\n",
              title, o.seeds);
      sylva_fit_report_table(of.f, &targets, &r);
      fprintf(of.f, "\nNursery %d years; %d trees grown in the calibration.\n", r.def.nursery,
              r.evaluations);
      rc = cli_outfile_close(&of, CLI_EXIT_OK);
    } else {
      rc = CLI_EXIT_FAILURE;
    }
    if (!rc && sylva_fit_report_png(png, title, &targets, &r, trees, count)) {
      fprintf(stderr, "sylva fit: %s: cannot write the picture\n", png);
      rc = CLI_EXIT_FAILURE;
    }
  }
  free(trees);
  if (rc) return rc;
  fprintf(stderr, "sylva fit: %s written in %.1f s\n", out_path, secs);
  printf("{\"nursery\": %d, \"trees_grown\": %d, \"max_error\": {\"height\": %.3f, \"dbh\": %.3f, "
         "\"crown_diameter\": %.3f, \"crown_height\": %.3f}}\n",
         r.def.nursery, r.evaluations, r.max_error[0], r.max_error[1], r.max_error[2],
         r.max_error[3]);
  return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}
