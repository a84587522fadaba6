/* sylva server: the store. Runs, their iterations (world snapshots with checksums,
 * lighter records in between), per-stem stats of every iteration and the log of
 * commands applied to a run, in one SQLite file (WAL; one transaction per stored
 * iteration, so after a crash the file holds a consistent prefix of every run).
 *
 * Snapshots are core images (sylva/snapshot.h), which carry their own checksum.
 * A store may be used from several threads: each call holds the store's own lock
 * for its statements and transaction (store_world_at only for each read, not
 * while it regrows), and store_error() gives the last failure of the calling
 * thread, as errno does.
 * Every function returns SERVER_OK or SERVER_EFAIL (SERVER_EINPUT where the
 * caller's input is at fault: not a sylva store, a newer schema, a missing file, a taken name); after
 * a failure store_error() says what failed, with the file's name and SQLite's
 * reason, e.g.
 *   "runs.db: storing iteration 12 of run \"oak\": disk I/O error". */
#ifndef SYLVA_SERVER_STORE_H
#define SYLVA_SERVER_STORE_H

#include "edit.h"
#include "server_error.h"
#include "sylva/run_status.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sylva/world.h"

/** PRAGMA application_id of a sylva store ("SYLV"). */
#define STORE_APPLICATION_ID 0x53594c56
/** Schema version this build writes (PRAGMA user_version). */
#define STORE_SCHEMA_VERSION 8
/** Default number of iterations between two full snapshots. */
#define STORE_SNAPSHOT_EVERY 5

typedef struct store store;

/** A run as stored. Strings are owned by the record (store_run_free). */
typedef struct store_run {
  int64_t id;
  char *name;
  char *scenario;     /**< the scenario, canonical JSON */
  uint64_t seed;
  int iterations;     /**< the iteration limit */
  int snapshot_every; /**< iterations between full snapshots */
  sylva_run_status status;
  char reason[16];    /**< finished or limit once it ended, else empty */
  char created[32], updated[32]; /**< UTC, ISO 8601 */
  int last_iteration; /**< the last stored iteration (0: only the planted world) */
  int64_t nodes;      /**< live nodes after it */
  int stems;          /**< stems at the last iteration with stats (plants an edit
                           added since are not counted until the next iteration) */
  /* the conflicts of that iteration's stats (docs/store.md): whether the run reports
   * them, the nodes inside its zones, and the stem and zone pairs that ever met */
  bool reports_conflicts;
  int64_t zone_nodes, zone_pairs;
  int start_year;     /**< the scenario's start_year; 0 when it gives none */
  bool years;         /**< a species of the scenario counts in years (stats carry ages) */
  bool stand;         /**< its stats carry the stand's (store_run_stand) */
} store_run;

/** Opens (create: also creates) a store file and brings its schema up to date
 *  inside one transaction. Refuses a file that is not SQLite, belongs to another
 *  program, or was written by a newer sylva. */
int store_open(const char *path, bool create, store **out);
/** Closes the store; NULL is fine. */
void store_close(store *st);
/** What the calling thread's last failing store call said (as errno is per thread). */
const char *store_error(const store *st);
/** The worlds the store restores from now on (store_load_world, store_world_at,
 *  before any regrowing) grow on this many threads (0 or 1: one; see
 *  sylva_world_set_threads; a thread count never changes a world). */
void store_set_threads(store *st, int threads);
/** The worlds the store restores from now on share t (sylva_world_share_threads;
 *  NULL: as store_set_threads says), which must outlive them. */
void store_share_threads(store *st, sylva_threads *t);

/** The message of a failed store_open (which has no store to ask). */
const char *store_open_error(void);

/** Creates a run with its planted world as iteration 0 (a full snapshot).
 *  Fails (store_error names it) when the name is taken. */
int store_create_run(store *st, const char *name, const char *scenario_json, uint64_t seed,
                     int iterations, int snapshot_every, const sylva_world *w, int64_t *run);
/** Finds a run by name; *found false when there is none. */
int store_find_run(store *st, const char *name, store_run *out, bool *found);
/** All runs, oldest first; *out is a malloc'd array of *count records. */
int store_list_runs(store *st, store_run **out, size_t *count);
/** Frees the strings of a record (and not the record). */
void store_run_free(store_run *r);
/** Frees an array from store_list_runs. */
void store_runs_free(store_run *runs, size_t count);

/** Stores one iteration in one transaction: its stats rows, its world hash and,
 *  when snapshot is true, the full world image. */
int store_save_iteration(store *st, int64_t run, const sylva_world *w,
                         const sylva_journal *j, bool snapshot);
/** The step-and-persist rule of every growing run (command line and daemon):
 *  stores iteration j with a full snapshot every `every` iterations and at the
 *  last one (the world finished, or j->iteration reached `limit`), the lighter
 *  record in between. */
int store_save_step(store *st, int64_t run, const sylva_world *w, const sylva_journal *j,
                    int every, int limit);
/** Whether store_save_step stores iteration j with its snapshot. */
bool store_step_snapshot(const sylva_world *w, const sylva_journal *j, int every, int limit);
/** Adds the world's snapshot to its iteration's row, stored before without one (the
 *  daemon stores an iteration's row, sends its delta, then adds the snapshot: a row
 *  without its snapshot is regrown from the one before, as after a damaged one). */
int store_save_snapshot(store *st, int64_t run, const sylva_world *w);
/** Sets a run's status (and reason, may be NULL) and iteration limit (> 0 to change). */
int store_set_status(store *st, int64_t run, sylva_run_status status, const char *reason,
                     int iterations);
/** The world hash stored for an iteration; *found false when there is no record. */
int store_iteration_hash(store *st, int64_t run, int iteration, uint64_t *hash, bool *found);
/** The world's hash by the definition the run keeps (docs/store.md, "The world hash");
 *  SERVER_EINPUT for a definition this build does not know. */
int store_world_hash(store *st, int64_t run, const sylva_world *w, uint64_t *hash);

/** Restores the newest good snapshot at or before iteration `at`. A snapshot whose
 *  checksum or content is bad is reported through warn (if given) and the previous
 *  one is used. *world_out gets the world, which is at iteration *from. */
int store_load_world(store *st, int64_t run, int at, void (*warn)(const char *msg),
                     sylva_world **world_out, int *from);

/** The world of a run at iteration `at`: the newest good snapshot at or before it,
 *  regrown to `at`. After each regrown iteration the commands logged at it are
 *  replayed (command_log.h) and the world is checked against the stored hash. */
int store_world_at(store *st, int64_t run, int at, void (*warn)(const char *msg),
                   sylva_world **world_out);

/** Records an edit applied to a run's world after its current iteration, in one
 *  transaction: the command is logged and that iteration's record (snapshot,
 *  hash) becomes the edited world, so restoring it needs no replay. */
int store_apply_edit(store *st, int64_t run, const sylva_world *w, const edit *e);

/** The scenario JSON of a run (malloc'd), for forks. */
int store_run_scenario(store *st, int64_t run, char **json);

/** A run's calendar: the scenario's start_year (0: none) and whether a species of it
 *  counts in years (store_run's start_year and years). */
int store_run_calendar(store *st, int64_t run, int *start_year, bool *years);

/** Whether a run's stats carry each stem's alive, died and vigour and each iteration's
 *  stand (docs/model.md, "Stands"): an iteration of it was stored with the stand's
 *  figures, as a world does whose lines give them (sylva_encode_stand). */
int store_run_stand(store *st, int64_t run, bool *stand);

/** One stored stats row. */
typedef struct store_stats_row {
  int iteration, stem, plant_stem, cap;
  const char *plant;
  double height, dbh, crown_width, crown_base, light; /**< NaN where null */
  int64_t nodes, shed;
  bool finished;
  int64_t pruned;                /**< -1 where the run does not report conflicts */
  const char *zones, *clearance; /**< compact JSON objects, or NULL (as pruned) */
  int age;                       /**< the stem's age in years (its plant's age at
                                      planting and the seasons since); -1 where null
                                      (a species without years) */
  double crown_height;           /**< NaN where null */
  double leaf_area;              /**< m^2; NaN where null (rows stored before schema 5) */
  /* docs/model.md, "Canopy cover" and "Wood and carbon"; NaN where null (rows stored
   * before schema 6, and the carbon measures where they do not apply) */
  double crown_area, wood_volume;          /**< m^2, m^3 */
  double biomass, biomass_model;           /**< kg */
  double carbon, co2, co2_sequestered;     /**< kg C, kg CO2, kg CO2 */
  double canopy_cover;                     /**< the iteration's, 0..1 */
  /* docs/model.md, "Stands": where the run's lines give them (sylva_encode_stand);
   * -1 or NaN where null (rows stored before schema 7, and runs without stands) */
  int alive;                     /**< 1 alive, 0 dead, -1 where null */
  int died;                      /**< the iteration it died, -1 while alive or null */
  double vigour;                 /**< NaN where null or none judged */
  sylva_stand_stats stand;       /**< the iteration's; alive and died -1 where null */
} store_stats_row;

/** Calls fn for every stats row of a run up to iteration `to`, in iteration then
 *  stem order; fn returns 0 to go on, non-zero to stop (returned as SERVER_EFAIL).
 *  The store stays locked meanwhile: fn must not call it. */
int store_each_stats(store *st, int64_t run, int to,
                     int (*fn)(const store_stats_row *row, void *ctx), void *ctx);

/** Calls fn for the age of every plant of a years species at the last stored
 *  iteration of its run (its first stem's `age`), in run then stem order; fn returns
 *  0 to go on. Plants an edit added show from the next stored iteration. */
int store_each_age(store *st, int (*fn)(int64_t run, const char *plant, int age, void *ctx),
                   void *ctx);

/** Appends a command record (command_log.h) applied to a run after iteration
 *  `iteration`. */
int store_log_command(store *st, int64_t run, int iteration, const char *command_json,
                      int64_t *seq);
/** Number of logged commands of a run. */
int store_command_count(store *st, int64_t run, int64_t *count);

#endif
