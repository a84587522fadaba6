/* sylva server: the subcommands. Each takes argv with argv[0] = its own name and
 * returns the process exit status. */
#ifndef SYLVA_SERVER_COMMANDS_H
#define SYLVA_SERVER_COMMANDS_H

/** `sylva run SCENARIO.json [options]`: grow a scenario headless. */
int cmd_run(int argc, char **argv);

/** `sylva validate SCENARIO.json`: check a scenario without running it. */
int cmd_validate(int argc, char **argv);

/** `sylva resume --db FILE --name NAME`: continue a stored run. */
int cmd_resume(int argc, char **argv);

/** `sylva runs --db FILE`: list the stored runs. */
int cmd_runs(int argc, char **argv);

/** `sylva export --db FILE --name NAME --format F -o OUT`: export a stored iteration. */
int cmd_export(int argc, char **argv);

/** `sylva render (--db FILE --name NAME | SCENARIO.json) -o OUT`: draw front, side
 *  and top views into a PNG, SVG or PDF file. */
int cmd_render(int argc, char **argv);

/** `sylva fit (DATA.csv | --utdb REGION:CODE) -o SPECIES.json`: calibrate a species in
 *  years to measured growth. */
int cmd_fit(int argc, char **argv);

/** `sylva species [--region R] | --utdb REGION:CODE`: the species library, or one
 *  species of the Urban Tree Database. */
int cmd_species(int argc, char **argv);

/** `sylva import FILE -o OUT.json`: a measured tree (a cylinder model) as a
 *  skeleton with estimated birth years. */
int cmd_import(int argc, char **argv);

/** `sylva sweep PLAN.json`: a plan's runs, locally, as a Slurm array job, or merged
 *  from its tasks' stores. */
int cmd_sweep(int argc, char **argv);

/** `sylva report --db FILE [--sweep NAME] [--years LIST] -o OUT.csv|html|pdf`: a sweep's
 *  runs compared at chosen years. */
int cmd_report(int argc, char **argv);

/** `sylva shade (--db FILE --name NAME [--iteration T | --year Y] | SCENARIO.json)
 *  --date MM-DD -o OUT.csv|json|png`: a day's hours of sun on ground and facades. */
int cmd_shade(int argc, char **argv);

/** `sylva site [--buildings FILE] [--trees FILE] [--zones FILE] ... -o SITE.json`: a
 *  scenario from GIS layers. */
int cmd_site(int argc, char **argv);

/** `sylva serve [options]`: the daemon. */
int cmd_serve(int argc, char **argv);

#endif
