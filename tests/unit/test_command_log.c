/* The command log's own record format (server/store/command_log.h,
 * docs/store.md): a record written by today's format replays, in memory and
 * through a real store file; encoding is byte-stable; records of format 0 (the
 * protocol-1 edit messages of older stores) still replay; plants with an age
 * need format 3, which only such edits are written in; bad and newer records are
 * refused with the place named. */
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "command_log.h"
#include "store.h"
#include "sylva/sylva.h"

/* A record exactly as this build writes it: keep it byte for byte. A change of
 * the format is a new format number, and this record must still replay. */
static const char today[] =
    "{\"format\":2,\"command\":\"edit\",\"remove_obstacles\":[\"wall\"],"
    "\"add_obstacles\":[{\"id\":\"board\",\"kind\":\"box\",\"min\":[1.25,-2,3],"
    "\"max\":[1.5,2,3.2]},{\"id\":\"crown\",\"kind\":\"zone\",\"min\":[-3,-3,0.45],"
    "\"max\":[3,3,6]}],"
    "\"add_plants\":[{\"id\":\"oak2\",\"species\":\"x\",\"roots\":[[-1,0.1,0]]},"
    "{\"id\":\"shrub2\",\"species\":\"x\",\"roots\":[[1,-1,0],[1.3,-1.2,0]]}],"
    "\"prune\":{\"zone\":\"crown\"}}";

/* A record of format 1 (before zones and pruning), as this build wrote it then. */
static const char format1[] =
    "{\"format\":1,\"command\":\"edit\",\"remove_obstacles\":[\"wall\"],"
    "\"add_obstacles\":[{\"id\":\"board\",\"kind\":\"box\",\"min\":[1.25,-2,3],"
    "\"max\":[1.5,2,3.2]}],"
    "\"add_plants\":[{\"id\":\"oak2\",\"species\":\"x\",\"roots\":[[-1,0.1,0]]},"
    "{\"id\":\"shrub2\",\"species\":\"x\",\"roots\":[[1,-1,0],[1.3,-1.2,0]]}]}";

/* The same edit as an older store logged it: the protocol-1 edit message. */
static const char format0[] =
    "{\"type\":\"edit\",\"run\":3,\"id\":\"e1\",\"remove_obstacles\":[\"wall\"],"
    "\"add_obstacles\":[{\"id\":\"board\",\"kind\":\"box\",\"min\":[1.25,-2,3],"
    "\"max\":[1.5,2,3.2]}],"
    "\"add_plants\":[{\"id\":\"oak2\",\"species\":\"x\",\"roots\":[[-1,0.1,0]]},"
    "{\"species\":\"x\",\"id\":\"shrub2\",\"roots\":[[1,-1,0],[1.3,-1.2,0]]}]}";

static sylva_world *site(void) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -3, wd.max[0] = wd.max[1] = 3, wd.max[2] = 6;
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  sp.growth.p[1] = 30;
  int s = sylva_world_add_species(w, &sp, "x");
  double root[1][3] = {{0, 0, 0}};
  sylva_plant_def pd = {s, "oak", (const double(*)[3])root, 1, 0, NULL, 0};
  sylva_world_add_plant(w, &pd, NULL);
  sylva_obstacle_def wall = {"wall", {-3, -3, 0}, {-2.8, 3, 2}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_world_add_obstacle(w, &wall);
  return w;
}

/* The edit of `format1`, made with the core's own calls. */
static void edit_by_hand_format1(sylva_world *w) {
  CHECK_INT(sylva_world_remove_obstacle(w, sylva_world_find_obstacle(w, "wall")), 0);
  sylva_obstacle_def board = {"board", {1.25, -2, 3}, {1.5, 2, 3.2}, SYLVA_OBSTACLE_SOLID, {0}};
  CHECK(sylva_world_add_obstacle(w, &board) >= 0);
  double r1[1][3] = {{-1, 0.1, 0}}, r2[2][3] = {{1, -1, 0}, {1.3, -1.2, 0}};
  sylva_plant_def a = {0, "oak2", (const double(*)[3])r1, 1, 0, NULL, 0};
  sylva_plant_def b = {0, "shrub2", (const double(*)[3])r2, 2, 0, NULL, 0};
  CHECK(sylva_world_add_plant(w, &a, NULL) >= 0);
  CHECK(sylva_world_add_plant(w, &b, NULL) >= 0);
}

/* The edit of `today`: format 1's, a zone over the crowns, and their pruning. */
static void edit_by_hand(sylva_world *w) {
  CHECK_INT(sylva_world_remove_obstacle(w, sylva_world_find_obstacle(w, "wall")), 0);
  sylva_obstacle_def board = {"board", {1.25, -2, 3}, {1.5, 2, 3.2}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_obstacle_def crown = {"crown", {-3, -3, 0.45}, {3, 3, 6}, SYLVA_OBSTACLE_ZONE, {0}};
  CHECK(sylva_world_add_obstacle(w, &board) >= 0);
  CHECK(sylva_world_add_obstacle(w, &crown) >= 0);
  double r1[1][3] = {{-1, 0.1, 0}}, r2[2][3] = {{1, -1, 0}, {1.3, -1.2, 0}};
  sylva_plant_def a = {0, "oak2", (const double(*)[3])r1, 1, 0, NULL, 0};
  sylva_plant_def b = {0, "shrub2", (const double(*)[3])r2, 2, 0, NULL, 0};
  CHECK(sylva_world_add_plant(w, &a, NULL) >= 0);
  CHECK(sylva_world_add_plant(w, &b, NULL) >= 0);
  CHECK(sylva_world_prune(w, crown.min, crown.max, NULL, NULL) > 0);
}

/* Decodes a record and applies it to a fresh site grown 4 iterations; the hash of
 * the result, 0 on any failure. */
static uint64_t replayed_hash(const char *record) {
  sylva_world *w = site(), *edited = NULL;
  for (int i = 0; i < 4; i++) sylva_world_step(w, NULL);
  edit e;
  char err[256] = "";
  int rc = command_log_decode(record, &e, err, sizeof err);
  CHECK_INT(rc, SERVER_OK);
  if (rc) fprintf(stderr, "  %s\n", err);
  if (!rc) CHECK_INT(edit_apply(w, &e, &edited, err, sizeof err), 0);
  edit_free(&e);
  uint64_t h = edited ? sylva_world_hash(edited) : 0;
  sylva_world_destroy(edited);
  sylva_world_destroy(w);
  return h;
}

/* Today's record gives the world the core's own calls give. */
static void test_today_replays(void) {
  sylva_world *w = site();
  for (int i = 0; i < 4; i++) sylva_world_step(w, NULL);
  edit_by_hand(w);
  CHECK(replayed_hash(today) == sylva_world_hash(w));
  CHECK_INT(sylva_world_plant_count(w), 3);
  sylva_world_destroy(w);
}

/* Encoding what was decoded gives the record back, byte for byte. */
static void test_encoding_is_stable(void) {
  edit e;
  char err[256];
  CHECK_INT(command_log_decode(today, &e, err, sizeof err), SERVER_OK);
  char *again = command_log_encode(&e);
  CHECK(again && strcmp(again, today) == 0);
  if (again && strcmp(again, today)) fprintf(stderr, "  encoded: %s\n", again);
  free(again);
  edit_free(&e);
  char *empty = command_log_encode(&e); /* the empty edit too */
  CHECK(empty && strcmp(empty, "{\"format\":2,\"command\":\"edit\",\"remove_obstacles\":[],"
                               "\"add_obstacles\":[],\"add_plants\":[]}") == 0);
  free(empty);
}

/* Older formats replay: format 1 as the core's calls give it, and a protocol-1 edit
 * message (format 0) as format 1. A zone or a prune is refused in format 1. */
static void test_format0_replays(void) {
  sylva_world *w = site();
  for (int i = 0; i < 4; i++) sylva_world_step(w, NULL);
  edit_by_hand_format1(w);
  CHECK(replayed_hash(format1) == sylva_world_hash(w));
  sylva_world_destroy(w);
  CHECK(replayed_hash(format0) == replayed_hash(format1));
  CHECK(replayed_hash(format0) != 0);
  CHECK(replayed_hash(format1) != replayed_hash(today));
  edit e;
  char err[256] = "";
  CHECK_INT(command_log_decode("{\"format\":1,\"command\":\"edit\",\"prune\":{\"zone\":\"a\"}}", &e,
                               err, sizeof err), SERVER_EINPUT);
  CHECK(strstr(err, "/prune: unknown key") != NULL);
  edit_free(&e);
  CHECK_INT(command_log_decode("{\"format\":1,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"z\","
                               "\"kind\":\"zone\",\"min\":[0,0,0],\"max\":[1,1,1]}]}", &e, err, sizeof err),
            SERVER_EINPUT);
  CHECK(strstr(err, "/add_obstacles/0/kind: expected \"box\"") != NULL);
  edit_free(&e);
}

/* An edit that plants an aged tree, as this build writes it (format 3: the oldest
 * format with ages; keep it byte for byte). */
static const char aged[] =
    "{\"format\":3,\"command\":\"edit\",\"remove_obstacles\":[],\"add_obstacles\":[],"
    "\"add_plants\":[{\"id\":\"lime\",\"species\":\"y\",\"roots\":[[-1,0.1,0]],\"age\":4}]}";

/* site() with a species "y" that counts in years, grown 4 iterations. */
static sylva_world *site_in_years(void) {
  sylva_world *w = site();
  sylva_species_def sp = sylva_default_species_def();
  sp.years = 1;
  CHECK_INT(sylva_world_add_species(w, &sp, "y"), 1);
  for (int i = 0; i < 4; i++) sylva_world_step(w, NULL);
  return w;
}

/* Decodes a record and applies it to site_in_years(); the status of the apply
 * (its message in err), *hash the edited world's. */
static int apply_record(const char *record, uint64_t *hash, char *err, size_t errlen) {
  sylva_world *w = site_in_years(), *edited = NULL;
  edit e;
  int rc = command_log_decode(record, &e, err, errlen);
  CHECK_INT(rc, SERVER_OK);
  if (!rc) rc = edit_apply(w, &e, &edited, err, errlen);
  *hash = edited ? sylva_world_hash(edited) : 0;
  edit_free(&e);
  sylva_world_destroy(edited);
  sylva_world_destroy(w);
  return rc;
}

/* A plant's age: written in format 3, read back byte for byte, replayed as the
 * core's own call plants it; refused for a species without years, and in format 2. */
static void test_aged_plant(void) {
  edit e;
  char err[256] = "";
  CHECK_INT(command_log_decode(aged, &e, err, sizeof err), SERVER_OK);
  CHECK(e.plant_count == 1 && e.plants[0].age == 4);
  char *again = command_log_encode(&e);
  CHECK(again && strcmp(again, aged) == 0);
  if (again && strcmp(again, aged)) fprintf(stderr, "  encoded: %s\n", again);
  free(again);
  edit_free(&e);

  sylva_world *w = site_in_years();
  double root[1][3] = {{-1, 0.1, 0}};
  sylva_plant_def lime = {1, "lime", (const double(*)[3])root, 1, 4, NULL, 0};
  CHECK(sylva_world_add_plant(w, &lime, NULL) >= 0);
  uint64_t h = 0;
  CHECK_INT(apply_record(aged, &h, err, sizeof err), SYLVA_OK);
  CHECK(h == sylva_world_hash(w));
  sylva_world_destroy(w);

  static const char igm[] =
      "{\"format\":3,\"command\":\"edit\",\"add_plants\":[{\"id\":\"oak2\",\"species\":\"x\","
      "\"roots\":[[-1,0.1,0]],\"age\":4}]}";
  CHECK_INT(apply_record(igm, &h, err, sizeof err), SYLVA_EINVAL);
  CHECK(strcmp(err, "/add_plants/0/age: species \"x\" has no time scale (years)") == 0);
  static const char *const bad[][2] = {
      {"{\"format\":2,\"command\":\"edit\",\"add_plants\":[{\"id\":\"a\",\"species\":\"y\","
       "\"roots\":[[0,0,0]],\"age\":4}]}",
       "/add_plants/0/age: unknown key"},
      {"{\"format\":3,\"command\":\"edit\",\"add_plants\":[{\"id\":\"a\",\"species\":\"y\","
       "\"roots\":[[0,0,0]],\"age\":501}]}",
       "/add_plants/0/age: expected an integer from 0 to 500"},
      {"{\"format\":3,\"command\":\"edit\",\"add_plants\":[{\"id\":\"a\",\"species\":\"y\","
       "\"roots\":[[0,0,0]],\"age\":2.5}]}",
       "/add_plants/0/age: expected an integer from 0 to 500"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    CHECK_INT(command_log_decode(bad[i][0], &e, err, sizeof err), SERVER_EINPUT);
    CHECK(strcmp(err, bad[i][1]) == 0);
    if (strcmp(err, bad[i][1])) fprintf(stderr, "  case %zu: got \"%s\"\n", i, err);
    edit_free(&e);
  }
}

/* Format 4: a prism with a hole and a prism zone, read back and re-encoded to the same
 * bytes, give the world the core's own calls give. */
static void test_prism_replays(void) {
  static const char prisms[] =
      "{\"format\":4,\"command\":\"edit\",\"remove_obstacles\":[],\"add_obstacles\":["
      "{\"id\":\"house\",\"kind\":\"prism\",\"polygon\":[[1,-2],[2.5,-1],[1.5,0.5],[0.5,-0.5]],"
      "\"holes\":[[[1.2,-1],[1.6,-1],[1.4,-0.6]]],\"z\":[0,2.5]},"
      "{\"id\":\"lane\",\"kind\":\"zone\",\"polygon\":[[-3,-1],[3,1],[3,2],[-3,0]],\"z\":[0.5,6]}],"
      "\"add_plants\":[]}";
  edit e;
  char err[256] = "";
  CHECK_INT(command_log_decode(prisms, &e, err, sizeof err), SERVER_OK);
  CHECK(e.obstacle_count == 2 && e.obstacles[0].ring_count == 2 && e.obstacles[0].point_count == 7 &&
        e.obstacles[1].ring_count == 1 && e.obstacles[1].kind == SYLVA_OBSTACLE_ZONE);
  char *again = command_log_encode(&e);
  CHECK(again && strcmp(again, prisms) == 0);
  if (again && strcmp(again, prisms)) fprintf(stderr, "  encoded: %s\n", again);
  free(again);
  edit_free(&e);

  sylva_world *w = site();
  for (int i = 0; i < 4; i++) sylva_world_step(w, NULL);
  double house_pts[7][2] = {{1, -2}, {2.5, -1}, {1.5, 0.5}, {0.5, -0.5}, {1.2, -1}, {1.6, -1}, {1.4, -0.6}};
  double lane_pts[4][2] = {{-3, -1}, {3, 1}, {3, 2}, {-3, 0}};
  int house_rings[2] = {4, 3}, lane_rings[1] = {4};
  sylva_obstacle_def house = {"house", {0, 0, 0}, {0, 0, 2.5}, SYLVA_OBSTACLE_SOLID,
                              {(const double(*)[2])house_pts, 7, house_rings, 2}};
  sylva_obstacle_def lane = {"lane", {0, 0, 0.5}, {0, 0, 6}, SYLVA_OBSTACLE_ZONE,
                             {(const double(*)[2])lane_pts, 4, lane_rings, 1}};
  CHECK(sylva_world_add_obstacle(w, &house) >= 0);
  CHECK(sylva_world_add_obstacle(w, &lane) >= 0);
  CHECK(replayed_hash(prisms) == sylva_world_hash(w));
  sylva_world_destroy(w);
}

/* Bad records name the place and the problem; nothing is half-read. */
static void test_bad_records(void) {
  static const struct {
    const char *record, *message;
  } cases[] = {
      {"{\"format\":5,\"command\":\"edit\"}",
       "/format: format 5 is newer than this sylva reads (up to 4)"},
      {"{\"format\":4,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"b\",\"kind\":\"prism\","
       "\"polygon\":[[0,0],[1,0],[1,1]],\"z\":[2,1]}]}",
       "/add_obstacles/0/z: to must be greater than from (1 <= 2)"},
      {"{\"format\":4,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"b\",\"kind\":\"prism\","
       "\"polygon\":[[0,0],[1,0],[2,0]],\"z\":[0,1]}]}",
       "/add_obstacles/0/polygon: the ring has no area"},
      {"{\"format\":3,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"b\",\"kind\":\"prism\","
       "\"polygon\":[[0,0],[1,0],[1,1]],\"z\":[0,1]}]}",
       "/add_obstacles/0/polygon: unknown key"},
      {"{\"format\":1.5,\"command\":\"edit\"}", "/format: expected an integer >= 1"},
      {"{\"format\":1,\"command\":\"prune\"}", "/command: expected \"edit\""},
      {"{\"format\":1,\"command\":\"edit\",\"colour\":1}", "/colour: unknown key"},
      {"{\"format\":1,\"command\":\"edit\",\"add_plants\":{}}", "/add_plants: expected an array"},
      {"{\"format\":1,\"command\":\"edit\",\"add_plants\":[{\"id\":\"a\",\"species\":\"x\","
       "\"roots\":[[0,0]]}]}",
       "/add_plants/0/roots/0: expected [x, y, z]"},
      {"{\"format\":1,\"command\":\"edit\",\"add_plants\":[{\"id\":\"a\",\"species\":\"x\","
       "\"roots\":[]}]}",
       "/add_plants/0/roots: expected a non-empty array"},
      {"{\"format\":1,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"\",\"kind\":\"box\","
       "\"min\":[0,0,0],\"max\":[1,1,1]}]}",
       "/add_obstacles/0/id: must be 1 to 63 bytes long"},
      {"{\"format\":1,\"command\":\"edit\",\"add_obstacles\":[{\"id\":\"b\",\"kind\":\"ball\","
       "\"min\":[0,0,0],\"max\":[1,1,1]}]}",
       "/add_obstacles/0/kind: expected \"box\""},
      {"{\"format\":1,\"command\":\"edit\",\"remove_obstacles\":[3]}",
       "/remove_obstacles/0: expected a string"},
      {"{\"type\":\"control\",\"run\":1}", "/type: expected \"edit\""},
      {"{\"format\":1,\"format\":1,\"command\":\"edit\"}", "/format: duplicate key"},
      {"[1]", "(root): expected an object"},
      {"{\"format\":", "(root): not JSON"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    edit e;
    char err[256] = "";
    CHECK_INT(command_log_decode(cases[i].record, &e, err, sizeof err), SERVER_EINPUT);
    bool named = strncmp(err, cases[i].message, strlen(cases[i].message)) == 0;
    CHECK(named);
    if (!named) fprintf(stderr, "  case %zu: got \"%s\"\n", i, err);
    edit_free(&e);
  }
}

/* Through a real store file: the record logged after iteration 3, whose stored
 * snapshot is gone, is replayed when iteration 6 is regrown from iteration 0, and
 * every regrown iteration matches its stored hash. */
static void test_store_replays_log(void) {
  char dir[] = "/tmp/sylva-log-XXXXXX", path[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/runs.db", dir);
  store *st = NULL;
  CHECK_INT(store_open(path, true, &st), 0);
  sylva_world *w = site();
  int64_t run = 0;
  CHECK_INT(store_create_run(st, "r", "{}", 1, 6, 100, w, &run), 0);
  for (int t = 1; t <= 6; t++) {
    const sylva_journal *j = NULL;
    CHECK_INT(sylva_world_step(w, &j), 0);
    if (t == 3) {
      edit_by_hand(w);
      CHECK_INT(store_log_command(st, run, 3, today, NULL), 0);
    }
    CHECK_INT(store_save_iteration(st, run, w, j, false), 0);
  }
  sylva_world *back = NULL;
  CHECK_INT(store_world_at(st, run, 6, NULL, &back), 0);
  if (!back) fprintf(stderr, "  %s\n", store_error(st));
  CHECK(back && sylva_world_hash(back) == sylva_world_hash(w));
  CHECK(back && sylva_world_plant_count(back) == 3);
  sylva_world_destroy(back);
  /* a record this build cannot read stops the regrowth with the command named */
  CHECK_INT(store_log_command(st, run, 5, "{\"format\":9,\"command\":\"edit\"}", NULL), 0);
  CHECK_INT(store_world_at(st, run, 6, NULL, &back), SERVER_EFAIL);
  CHECK(back == NULL);
  CHECK(strstr(store_error(st), "replaying command 2 after iteration 5: /format: format 9") !=
        NULL);
  store_close(st);
  sylva_world_destroy(w);
  unlink(path);
  char side[300];
  snprintf(side, sizeof side, "%s-wal", path);
  unlink(side);
  snprintf(side, sizeof side, "%s-shm", path);
  unlink(side);
  rmdir(dir);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(today_replays), CHECK_TEST(encoding_is_stable),
                                     CHECK_TEST(format0_replays), CHECK_TEST(bad_records),
                                     CHECK_TEST(store_replays_log), CHECK_TEST(aged_plant),
                                     CHECK_TEST(prism_replays)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("command log");
}
