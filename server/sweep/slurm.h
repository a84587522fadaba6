/* sylva server: a sweep as a Slurm array job (docs/cli.md, "sweep"): the sbatch
 * script that gives each array task its share of the runs and a store of its own,
 * and its submission. */
#ifndef SYLVA_SERVER_SLURM_H
#define SYLVA_SERVER_SLURM_H

#include <stdbool.h>
#include <stddef.h>

/** The script's name in its folder. */
#define SLURM_SCRIPT "sweep.sbatch"

/** What the script runs. Paths are made absolute (the tasks start elsewhere). */
typedef struct slurm_script {
  const char *dir;  /**< the folder of the script, the task stores and their logs */
  const char *exe;  /**< the sylva binary every node runs */
  const char *plan; /**< the plan file */
  int tasks;        /**< array tasks: task K grows the runs at positions K, K + T, ... */
  int jobs;         /**< processes per task */
  int threads;      /**< threads per process (--cpus-per-task: jobs x threads) */
  int runs;         /**< the plan's runs (for the script's comment) */
  bool force;       /**< the plan has more than SWEEP_MAX_RUNS runs: the tasks need --force */
} slurm_script;

/** Creates dir if need be and writes dir/sweep.sbatch; *path gets its path
 *  (malloc'd). 0, or -1 with err. */
int slurm_write_script(const slurm_script *s, char **path, char *err, size_t errlen);
/** The number of array tasks of the script in dir (as written by slurm_write_script).
 *  0, or -1 with err. */
int slurm_script_tasks(const char *dir, int *tasks, char *err, size_t errlen);
/** The path of task k's store in dir (malloc'd). */
char *slurm_task_store(const char *dir, int k);
/** Submits the script with `sbatch --parsable`; jobid gets the job's id. 0, or -1
 *  with err (sbatch missing, or what it said). */
int slurm_submit(const char *script, char *jobid, size_t idlen, char *err, size_t errlen);

#endif
