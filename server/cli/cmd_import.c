/* `sylva import`: a measured tree (a quantitative structure model of cylinders) as a
 * sylva skeleton of internodes, each node with its estimated birth year (docs/cli.md,
 * "import"; server/import/tree.h). */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "fit.h"
#include "measured.h"
#include "options.h"
#include "outfile.h"
#include "qsm.h"
#include "sylva/library.h"
#include "tree.h"

enum {
  OPT_FORMAT, OPT_MODEL, OPT_SPECIES, OPT_AGE, OPT_RHO, OPT_BEFORE, OPT_OUT, OPT_HELP, OPT_COUNT
};

static const cli_option import_options[OPT_COUNT] = {
    [OPT_FORMAT] = {"format", 0, "F", "mat, text, csv or skeleton (default: from the file)"},
    [OPT_MODEL] = {"model", 0, "K", "the file's K-th model, from 1 (default 1)"},
    [OPT_SPECIES] = {"species", 0, "NAME", "a library species (default utdb:NoEast:PLAC)"},
    [OPT_AGE] = {"age", 0, "A", "the tree's age in years (default: from its height)"},
    [OPT_RHO] = {"rho", 0, "M", "internode length in m (0.01-2; default the species')"},
    [OPT_BEFORE] = {"years-before", 0, "N", "write the tree as it was N years before"},
    [OPT_OUT] = {"output", 'o', "FILE", "the skeleton (sylva.skeleton/1 JSON) to write (required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

#define DEFAULT_SPECIES "utdb:NoEast:PLAC"

static void import_usage(FILE *f) {
  fputs("Usage: sylva import FILE -o OUT.json [OPTIONS]\n"
        "\n"
        "Turns a measured tree, a quantitative structure model of cylinders (TreeQSM .mat\n"
        "or text, SimpleForest CSV, or a sylva.skeleton/1 file), into a sylva skeleton of\n"
        "internodes of the species' length rho. Each node gets its estimated birth year\n"
        "(0 the season of the measurement, earlier years negative) from its path to the\n"
        "tips, its height and the species' own growth curve, scaled to the tree's\n"
        "height at its age. Pieces of the model that float above the ground are\n"
        "left out; roots that start on the ground are stems of their own.\n"
        "\n"
        "OUT.json holds one plant, \"imported\", one stem per root; with --years-before N\n"
        "the tree as it was N years before (the nodes born by then, radii by the pipe\n"
        "model). stdout gets one JSON line: cylinders, nodes, height, dbh, volume,\n"
        "length, branches, max_order, age, stems, pieces_dropped, and the file's own\n"
        "treedata when it has them. Bad input exits 2 and writes nothing.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, import_options, OPT_COUNT);
}

/* cJSON builders that remember a failed allocation in *ok. */
static cJSON *add_number(cJSON *obj, const char *key, double v, bool *ok) {
  cJSON *n = cJSON_AddNumberToObject(obj, key, v);
  if (!n) *ok = false;
  return n;
}

static cJSON *add_item(cJSON *array, cJSON *item, bool *ok) {
  if (!item || !cJSON_AddItemToArray(array, item)) {
    cJSON_Delete(item);
    *ok = false;
    return NULL;
  }
  return item;
}

/* Adds an array of n numbers to obj under key; false (and *ok false) on failure. */
static bool add_numbers(cJSON *obj, const char *key, const double *v, int n, bool *ok) {
  cJSON *a = cJSON_CreateDoubleArray(v, n);
  if (!a || !cJSON_AddItemToObject(obj, key, a)) {
    cJSON_Delete(a);
    *ok = false;
    return false;
  }
  return true;
}

static double rounded(double v, double scale) { return round(v * scale) / scale; }

/* The tree as sylva.skeleton/1 (docs/cli.md, "The skeleton format"). */
static cJSON *skeleton_json(const sylva_tree *t, double rho, bool *ok) {
  cJSON *doc = cJSON_CreateObject();
  if (!doc) {
    *ok = false;
    return NULL;
  }
  if (!cJSON_AddStringToObject(doc, "format", "sylva.skeleton/1")) *ok = false;
  add_number(doc, "iteration", 0, ok);
  add_number(doc, "voxel", rho / 2, ok); /* the scenario's default voxel for the species */
  double lo[3] = {t->base[0], t->base[1], t->base[2]}, hi[3] = {t->base[0], t->base[1], t->base[2]};
  for (size_t i = 0; i < t->count; i++)
    for (int j = 0; j < 3; j++) {
      lo[j] = fmin(lo[j], t->node[i].p[j]);
      hi[j] = fmax(hi[j], t->node[i].p[j]);
    }
  for (int j = 0; j < 3; j++) {
    lo[j] = floor(lo[j]);
    hi[j] = ceil(hi[j]) + (j == 2 ? 1 : 0);
  }
  cJSON *world = cJSON_AddObjectToObject(doc, "world");
  if (!world || !add_numbers(world, "min", lo, 3, ok) || !add_numbers(world, "max", hi, 3, ok))
    *ok = false;
  if (!cJSON_AddArrayToObject(doc, "obstacles")) *ok = false;
  cJSON *plants = cJSON_AddArrayToObject(doc, "plants");
  cJSON *plant = plants ? add_item(plants, cJSON_CreateObject(), ok) : NULL;
  cJSON *stems = NULL;
  if (!plant || !cJSON_AddStringToObject(plant, "id", "imported") ||
      !(stems = cJSON_AddArrayToObject(plant, "stems"))) {
    *ok = false;
    return doc;
  }
  cJSON *nodes = NULL;
  for (size_t i = 0; i < t->count && *ok; i++) {
    const sylva_tree_node *n = &t->node[i];
    if (n->parent < 0) { /* a stem's nodes are contiguous, its root first */
      cJSON *stem = add_item(stems, cJSON_CreateObject(), ok);
      double root[3];
      for (int j = 0; j < 3; j++) root[j] = rounded(n->p[j], 1e4);
      if (!stem || !add_numbers(stem, "root", root, 3, ok) ||
          !(nodes = cJSON_AddArrayToObject(stem, "nodes"))) {
        *ok = false;
        break;
      }
    }
    /* positions to 4 decimals, radii to 5 (at least 0.00001 m), as run --export */
    double v[7] = {(double)i,
                   (double)n->parent,
                   rounded(n->p[0], 1e4),
                   rounded(n->p[1], 1e4),
                   rounded(n->p[2], 1e4),
                   fmax(rounded(n->radius, 1e5), 1e-5),
                   (double)n->birth};
    add_item(nodes, cJSON_CreateDoubleArray(v, 7), ok);
  }
  return doc;
}

/* The summary line. */
static char *summary_json(const sylva_qsm *q, const sylva_tree *t, int years_before) {
  bool ok = true;
  cJSON *s = cJSON_CreateObject();
  if (!s) return NULL;
  add_number(s, "cylinders", (double)q->count, &ok);
  add_number(s, "nodes", (double)t->count, &ok);
  add_number(s, "height", rounded(t->height, 1e4), &ok);
  add_number(s, "dbh", rounded(t->dbh, 1e4), &ok); /* NaN prints as null */
  add_number(s, "volume", rounded(t->volume, 1e6), &ok);
  add_number(s, "length", rounded(t->length, 1e3), &ok);
  add_number(s, "branches", t->branches, &ok);
  add_number(s, "max_order", t->max_order, &ok);
  add_number(s, "age", t->age, &ok);
  if (years_before >= 0) add_number(s, "years_before", years_before, &ok);
  add_number(s, "stems", t->stems, &ok);
  add_number(s, "pieces_dropped", (double)t->pieces_dropped, &ok);
  if (q->has_treedata) {
    const sylva_qsm_treedata *d = &q->treedata;
    cJSON *td = cJSON_AddObjectToObject(s, "treedata");
    if (!td) ok = false;
    else {
      add_number(td, "height", rounded(d->height, 1e4), &ok);
      add_number(td, "dbh", rounded(d->dbh, 1e4), &ok);
      add_number(td, "volume", rounded(d->total_volume / 1000.0, 1e6), &ok);
      add_number(td, "length", rounded(d->total_length, 1e3), &ok);
      add_number(td, "branches", d->branches, &ok);
      add_number(td, "max_order", d->max_order, &ok);
    }
  }
  char *text = ok ? cJSON_PrintUnformatted(s) : NULL;
  cJSON_Delete(s);
  return text;
}

int cmd_import(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "import", import_options, OPT_COUNT, argc, argv);
  const char *out_path = NULL, *species = DEFAULT_SPECIES, *arg;
  sylva_qsm_format format = SYLVA_QSM_UNKNOWN;
  int model = 0, age = 0, years_before = -1, first = argc, opt;
  double rho = 0;
  uint64_t v;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_FORMAT:
      format = sylva_qsm_format_named(arg);
      if (format == SYLVA_QSM_UNKNOWN)
        return cli_usage_error("import", "--format: '%s' is not mat, text, csv or skeleton", arg);
      break;
    case OPT_MODEL:
      if (cli_parse_u64("import", "model", arg, 1, 1000000, &v)) return CLI_EXIT_USAGE;
      model = (int)v;
      break;
    case OPT_SPECIES: species = arg; break;
    case OPT_AGE:
      if (cli_parse_u64("import", "age", arg, 1, SYLVA_MAX_AGE, &v)) return CLI_EXIT_USAGE;
      age = (int)v;
      break;
    case OPT_RHO: {
      char *end;
      errno = 0;
      double r = strtod(arg, &end);
      if (end == arg || *end || errno || !(r >= 0.01 && r <= 2.0))
        return cli_usage_error("import", "--rho: '%s' is not a length from 0.01 to 2 m", arg);
      rho = r;
      break;
    }
    case OPT_BEFORE:
      if (cli_parse_u64("import", "years-before", arg, 0, SYLVA_FIT_MAX_YEARS, &v))
        return CLI_EXIT_USAGE;
      years_before = (int)v;
      break;
    case OPT_OUT: out_path = arg; break;
    default: import_usage(stdout); return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  const char *path = first < argc ? argv[first] : NULL;
  if (first + 1 < argc)
    return cli_usage_error("import", "unexpected argument '%s'", argv[first + 1]);
  if (!path) return cli_usage_error("import", "FILE is required");
  if (!out_path || !out_path[0]) return cli_usage_error("import", "-o FILE is required");

  sylva_species_def def;
  int rc = sylva_library_find(species, &def);
  if (rc == SYLVA_ENOMEM) {
    fprintf(stderr, "sylva: out of memory\n");
    return CLI_EXIT_FAILURE;
  }
  if (rc) {
    char list[1024];
    sylva_library_names(list, sizeof list);
    return cli_usage_error("import", "--species: unknown library species '%s' (the library: %s)",
                           species, list);
  }
  /* the same curve a scenario's measured plant is dated on */
  static double heights[SYLVA_MAX_AGE + 1];
  int years = sylva_import_curve(&def, age, heights);

  sylva_qsm q = {0};
  char err[1024] = "";
  rc = sylva_qsm_read(path, format, model, &q, err, sizeof err);
  if (rc) {
    fprintf(stderr, "sylva: %s\n", err);
    return rc == SYLVA_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  sylva_tree_options o = {.rho = rho > 0 ? rho : def.rho,
                          .heights = heights,
                          .years = years,
                          .age = age,
                          .pipe_exponent = def.pipe_exponent};
  sylva_tree tree, stage = {0};
  rc = sylva_tree_build(&q, &o, &tree, err, sizeof err);
  if (rc) {
    fprintf(stderr, "sylva: %s: %s\n", path, err);
    sylva_qsm_free(&q);
    return rc == SYLVA_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  const sylva_tree *t = &tree;
  if (years_before > tree.age) {
    fprintf(stderr, "sylva: --years-before %d: the tree is %d years old\n", years_before,
            tree.age);
    rc = CLI_EXIT_USAGE;
    goto done;
  }
  if (years_before >= 0) {
    if (sylva_tree_stage(&tree, years_before, def.pipe_exponent, &stage)) {
      fprintf(stderr, "sylva: out of memory\n");
      rc = CLI_EXIT_FAILURE;
      goto done;
    }
    t = &stage;
  }
  bool ok = true;
  cJSON *doc = skeleton_json(t, o.rho, &ok);
  char *text = ok ? cJSON_PrintUnformatted(doc) : NULL;
  cJSON_Delete(doc);
  char *line = text ? summary_json(&q, t, years_before) : NULL;
  if (!line) {
    fprintf(stderr, "sylva: out of memory\n");
    free(text);
    rc = CLI_EXIT_FAILURE;
    goto done;
  }
  cli_outfile of;
  rc = cli_outfile_open(&of, "-o", out_path, false);
  if (!rc) {
    fputs(text, of.f);
    fputc('\n', of.f);
    rc = cli_outfile_close(&of, CLI_EXIT_OK);
  }
  free(text);
  if (!rc) {
    printf("%s\n", line);
    if (fflush(stdout) != 0) rc = CLI_EXIT_FAILURE;
  }
  free(line);

done:
  sylva_tree_free(&stage);
  sylva_tree_free(&tree);
  sylva_qsm_free(&q);
  return rc;
}
