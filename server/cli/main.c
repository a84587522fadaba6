/* sylva: the command-line entry point; dispatches to the subcommands. */
#include <malloc.h>
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "options.h"

#ifndef SYLVA_VERSION
#define SYLVA_VERSION "unknown"
#endif

static void usage(FILE *f) {
  fputs("Usage: sylva COMMAND [OPTIONS]\n"
        "\n"
        "Grow trees, shrubs and stands that compete for light in a shared voxel world\n"
        "(Integrated Growth Modeling on Light-Guided Tree Modeling).\n"
        "\n"
        "Commands:\n"
        "  run SCENARIO.json       grow a scenario headless; one JSON line per iteration\n"
        "  validate SCENARIO.json  check a scenario without running it\n"
        "  resume --db FILE --name NAME\n"
        "                          continue a stored run\n"
        "  runs --db FILE          list the stored runs\n"
        "  export --db FILE --name NAME --format F -o OUT\n"
        "                          a stored iteration as skeleton, obj, ply, csv or glb\n"
        "  render (--db FILE --name NAME | SCENARIO.json) -o OUT.png|svg|pdf\n"
        "                          front, side and top views of a stored iteration or\n"
        "                          of a scenario grown to its end\n"
        "  serve                   the daemon: grows runs, streams them over WebSockets\n"
        "  fit (DATA.csv | --utdb REGION:CODE) -o SPECIES.json\n"
        "                          calibrate a species in years to measured growth\n"
        "  species [--region R]    the species library (Urban Tree Database species)\n"
        "  import FILE -o OUT.json\n"
        "                          a measured tree (TreeQSM, SimpleForest) as a skeleton\n"
        "                          with estimated birth years\n"
        "  sweep PLAN.json (--db OUT.db | --slurm DIR | --merge DIR --db OUT.db)\n"
        "                          a plan's runs (species, seeds, variants), locally or\n"
        "                          as a Slurm array job\n"
        "  report --db FILE [--sweep NAME] [--years LIST] -o OUT.csv|html|pdf\n"
        "                          a sweep's runs compared at chosen years\n"
        "  shade (--db FILE --name NAME | SCENARIO.json) --date MM-DD -o OUT.csv|json|png\n"
        "                          a day's hours of sun on the ground and facades\n"
        "  site [--buildings FILE] [--trees FILE] [--zones FILE] -o SITE.json\n"
        "                          a scenario from GIS layers: buildings, zones, trees\n"
        "\n"
        "Options:\n"
        "  -h, --help              show this help\n"
        "      --version           show the version\n"
        "\n"
        "'sylva COMMAND --help' describes the options of a command.\n"
        "Exit status: 0 success, 1 runtime failure, 2 bad usage or bad input.\n",
        f);
}

int main(int argc, char **argv) {
  /* Blocks of 1 MB and more (a world's voxel slabs, skeleton and per-slot scratch)
   * straight from the system: grown in place by mremap and given back whole when
   * freed. Left to glibc's sliding threshold they sat in the heap below 32 MB, and
   * every growth left the old copy behind as a hole: 94 MB of a 1.17 GB hectare
   * (docs/performance.md, "Memory"). */
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
  if (argc < 2) {
    usage(stderr);
    return CLI_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0) {
    usage(stdout);
    return CLI_EXIT_OK;
  }
  if (strcmp(cmd, "--version") == 0) {
    printf("sylva %s\n", SYLVA_VERSION);
    return CLI_EXIT_OK;
  }
  if (strcmp(cmd, "run") == 0) return cmd_run(argc - 1, argv + 1);
  if (strcmp(cmd, "validate") == 0) return cmd_validate(argc - 1, argv + 1);
  if (strcmp(cmd, "resume") == 0) return cmd_resume(argc - 1, argv + 1);
  if (strcmp(cmd, "runs") == 0) return cmd_runs(argc - 1, argv + 1);
  if (strcmp(cmd, "export") == 0) return cmd_export(argc - 1, argv + 1);
  if (strcmp(cmd, "render") == 0) return cmd_render(argc - 1, argv + 1);
  if (strcmp(cmd, "serve") == 0) return cmd_serve(argc - 1, argv + 1);
  if (strcmp(cmd, "fit") == 0) return cmd_fit(argc - 1, argv + 1);
  if (strcmp(cmd, "species") == 0) return cmd_species(argc - 1, argv + 1);
  if (strcmp(cmd, "import") == 0) return cmd_import(argc - 1, argv + 1);
  if (strcmp(cmd, "sweep") == 0) return cmd_sweep(argc - 1, argv + 1);
  if (strcmp(cmd, "report") == 0) return cmd_report(argc - 1, argv + 1);
  if (strcmp(cmd, "shade") == 0) return cmd_shade(argc - 1, argv + 1);
  if (strcmp(cmd, "site") == 0) return cmd_site(argc - 1, argv + 1);
  if (cmd[0] == '-')
    fprintf(stderr, "sylva: unknown option '%s'\n", cmd);
  else
    fprintf(stderr, "sylva: unknown command '%s'\n", cmd);
  fputs("Try 'sylva --help'.\n", stderr);
  return CLI_EXIT_USAGE;
}
