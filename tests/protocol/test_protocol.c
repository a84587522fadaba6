/* The protocol messages (proto/include/sylva/protocol.h): parsing of every client
 * message and of every kind of bad one, JSONTestSuite raw and wrapped, the
 * encoders' JSON, a snapshot plus deltas that reproduce the skeleton, and the
 * light slice.
 *
 * With --jsontestsuite DIR: the JSONTestSuite test_parsing files only (exit 77,
 * skipped, when DIR is missing). A test's name as the last argument runs it alone. */
#include "../read_file.h"
#include <cjson/cJSON.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../list_dir.h"
#include "sylva/encode.h"
#include "sylva/json_check.h"
#include "sylva/protocol.h"
#include "sylva/scenario.h"
#include "sylva/snapshot.h"
#include "sylva/status.h"
#include "sylva/world.h"

/* ---- helpers ---- */

#define CHECK_STR(a, b)                                                                     \
  do {                                                                                      \
    const char *check_a_ = (a), *check_b_ = (b);                                            \
    if (check_a_ && check_b_ && strcmp(check_a_, check_b_) == 0) check_passed++;            \
    else {                                                                                  \
      check_failed++;                                                                       \
      fprintf(stderr, "%s:%d: %s == %s failed: \"%s\" != \"%s\"\n", __FILE__, __LINE__, #a, \
              #b, check_a_ ? check_a_ : "(null)", check_b_ ? check_b_ : "(null)");          \
    }                                                                                       \
  } while (0)

/* Parses text that must be valid; the message is returned for inspection. */
static bool parse_ok_at(const char *text, sylva_msg *m, int line) {
  char err[512];
  int rc = sylva_msg_parse(text, strlen(text), m, err, sizeof err);
  if (rc == 0) {
    check_passed++;
    return true;
  }
  check_failed++;
  fprintf(stderr, "%s:%d: parse failed (%d): %s\n  input: %.300s\n", __FILE__, line, rc, err, text);
  return false;
}
#define PARSE_OK(text, m) parse_ok_at((text), (m), __LINE__)

/* Parses text that must be rejected with SYLVA_EINVAL and a message containing want
 * (and the message must start with a pointer, "(root)" or "(syntax)"). */
static void parse_bad_at(const char *text, size_t len, const char *want, int line) {
  char err[512];
  sylva_msg m;
  int rc = sylva_msg_parse(text, len, &m, err, sizeof err);
  bool ok = rc == SYLVA_EINVAL && strstr(err, want) != NULL &&
            (err[0] == '/' || strncmp(err, "(root)", 6) == 0 || strncmp(err, "(syntax)", 8) == 0);
  if (ok) {
    check_passed++;
  } else {
    check_failed++;
    fprintf(stderr, "%s:%d: expected an error containing \"%s\", got %d \"%s\"\n  input: %.300s\n",
            __FILE__, line, want, rc, rc ? err : "", text);
  }
  sylva_msg_free(&m);
}
#define PARSE_BAD(text, want) parse_bad_at((text), strlen(text), (want), __LINE__)

/* Checks that text is one strict JSON value and cJSON reads it; returns the tree. */
static cJSON *valid_json_at(const char *text, int line) {
  char err[256];
  if (!text) {
    check_failed++;
    fprintf(stderr, "%s:%d: encoder returned NULL\n", __FILE__, line);
    return NULL;
  }
  if (sylva_json_check(text, strlen(text), 1000, err, sizeof err) != 0) {
    check_failed++;
    fprintf(stderr, "%s:%d: invalid JSON (%s): %.300s\n", __FILE__, line, err, text);
    return NULL;
  }
  cJSON *root = cJSON_Parse(text);
  if (!root) {
    check_failed++;
    fprintf(stderr, "%s:%d: cJSON cannot read: %.300s\n", __FILE__, line, text);
    return NULL;
  }
  check_passed++;
  return root;
}
#define VALID_JSON(text) valid_json_at((text), __LINE__)

static const char *str_of(const cJSON *obj, const char *key) {
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  return cJSON_IsString(item) ? item->valuestring : NULL;
}

static double num_of(const cJSON *obj, const char *key) {
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  return cJSON_IsNumber(item) ? item->valuedouble : NAN;
}

/* ---- valid messages ---- */

static const char *const small_scenario =
    "{\"format\":\"sylva.scenario/1\",\"name\":\"s\",\"world\":{\"min\":[-2,-2,0],\"max\":[2,2,4]},"
    "\"species\":{\"oak\":{\"preset\":\"igm-fig11\"}},"
    "\"plants\":[{\"id\":\"t1\",\"species\":\"oak\",\"roots\":[[0,0,0]]}]}";

/* hello, without and with a token; the id is kept as its JSON text. */
static void test_valid_hello(void) {
  sylva_msg m;
  if (PARSE_OK("{\"type\":\"hello\"}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_HELLO);
    CHECK(m.token == NULL);
    CHECK(m.ref == NULL);
  }
  sylva_msg_free(&m);
  if (PARSE_OK(" {\"type\": \"hello\", \"token\": \"s3cr\\u00e9t\", \"id\": \"a\\\"b\"} ", &m)) {
    CHECK_STR(m.token, "s3cr\xc3\xa9t");
    CHECK_STR(m.ref, "\"a\\\"b\"");
  }
  sylva_msg_free(&m);
}

/* A numeric id is kept as its shortest number text. */
static void test_valid_numeric_ids(void) {
  sylva_msg m;
  if (PARSE_OK("{\"id\":12,\"type\":\"list\"}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_LIST);
    CHECK_STR(m.ref, "12");
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"id\":-0.5e1,\"type\":\"scenarios\"}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_SCENARIOS);
    CHECK_STR(m.ref, "-5");
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"id\":1.25,\"type\":\"list\"}", &m)) CHECK_STR(m.ref, "1.25");
  sylva_msg_free(&m);
}

/* create: the scenario parsed; name, start and id when given. */
static void test_valid_create(void) {
  sylva_msg m;
  char text[4096];
  snprintf(text, sizeof text, "{\"type\":\"create\",\"scenario\":%s}", small_scenario);
  if (PARSE_OK(text, &m)) {
    CHECK_INT(m.type, SYLVA_MSG_CREATE);
    CHECK(m.scenario != NULL);
    CHECK(m.name == NULL);
    CHECK(!m.start);
    if (m.scenario) {
      CHECK_INT(m.scenario->plant_count, 1);
      CHECK_STR(m.scenario->name, "s");
    }
  }
  sylva_msg_free(&m);
  snprintf(text, sizeof text,
           "{\"type\":\"create\",\"id\":\"c1\",\"name\":\"Oak "
           "\xc3\xa9t\xc3\xa9\",\"start\":true,\"scenario\":%s}",
           small_scenario);
  if (PARSE_OK(text, &m)) {
    CHECK_STR(m.name, "Oak \xc3\xa9t\xc3\xa9");
    CHECK(m.start);
    CHECK_STR(m.ref, "\"c1\"");
  }
  sylva_msg_free(&m);
}

/* create of an empty site, to be planted by edits: no plants, or an empty list. */
static void test_valid_create_empty_site(void) {
  /* (a scenario file needs plants: `sylva run` and `validate` refuse both) */
  static const char *const empty_sites[] = {"", ",\"plants\":[]"};
  for (size_t i = 0; i < sizeof empty_sites / sizeof empty_sites[0]; i++) {
    sylva_msg m;
    char text[4096];
    snprintf(text, sizeof text,
             "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/1\","
             "\"world\":{\"min\":[-2,-2,0],\"max\":[2,2,4]}%s}}",
             empty_sites[i]);
    if (PARSE_OK(text, &m)) {
      CHECK(m.scenario != NULL);
      if (m.scenario) CHECK_INT(m.scenario->plant_count, 0);
    }
    sylva_msg_free(&m);
  }
}

/* subscribe with and without since, runs up to 2^53 - 1; unsubscribe. */
static void test_valid_subscribe(void) {
  sylva_msg m;
  if (PARSE_OK("{\"type\":\"subscribe\",\"run\":3}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_SUBSCRIBE);
    CHECK_INT(m.run, 3);
    CHECK(!m.has_since);
    CHECK_INT(m.detail, SYLVA_DETAIL_NODES);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"subscribe\",\"run\":3,\"detail\":\"stems\",\"since\":2}", &m)) {
    CHECK_INT(m.detail, SYLVA_DETAIL_STEMS);
    CHECK_INT(m.since, 2);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"subscribe\",\"run\":3,\"detail\":\"nodes\"}", &m))
    CHECK_INT(m.detail, SYLVA_DETAIL_NODES);
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"subscribe\",\"run\":9007199254740991,\"since\":0}", &m)) {
    CHECK_INT(m.run, 9007199254740991LL);
    CHECK(m.has_since);
    CHECK_INT(m.since, 0);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"subscribe\",\"run\":1.0e0,\"since\":41}", &m)) {
    CHECK_INT(m.run, 1);
    CHECK_INT(m.since, 41);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"unsubscribe\",\"run\":2}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_UNSUBSCRIBE);
    CHECK_INT(m.run, 2);
  }
  sylva_msg_free(&m);
}

/* control: every action, a count of 1 by default and up to 100000 for step. */
static void test_valid_control(void) {
  static const char *const actions[] = {"start", "pause", "step", "stop"};
  static const sylva_control_action codes[] = {SYLVA_CONTROL_START, SYLVA_CONTROL_PAUSE,
                                               SYLVA_CONTROL_STEP, SYLVA_CONTROL_STOP};
  sylva_msg m;
  char text[4096];
  for (int i = 0; i < 4; i++) {
    snprintf(text, sizeof text, "{\"type\":\"control\",\"run\":5,\"action\":\"%s\"}", actions[i]);
    if (PARSE_OK(text, &m)) {
      CHECK_INT(m.type, SYLVA_MSG_CONTROL);
      CHECK_INT(m.action, codes[i]);
      CHECK_INT(m.count, 1);
      CHECK_INT(m.run, 5);
    }
    sylva_msg_free(&m);
  }
  if (PARSE_OK("{\"type\":\"control\",\"run\":5,\"action\":\"step\",\"count\":100000}", &m))
    CHECK_INT(m.count, 100000);
  sylva_msg_free(&m);
}

/* edit: plants, obstacles and removals, each list optional and possibly empty. */
static void test_valid_edit(void) {
  sylva_msg m;
  if (PARSE_OK("{\"type\":\"edit\",\"run\":4}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_EDIT);
    CHECK_INT(m.add_plant_count + m.add_obstacle_count + m.remove_obstacle_count, 0);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"edit\",\"run\":4,\"add_plants\":[{\"id\":\"t9\",\"species\":\"oak\","
               "\"roots\":[[1,2,0],[1.5,2,0]]},{\"id\":\"t10\",\"species\":\"pine\",\"roots\":[[0,"
               "0,0]]}],"
               "\"add_obstacles\":[{\"id\":\"board\",\"kind\":\"box\",\"min\":[0,0,3],\"max\":[1,1,"
               "3.1]}],"
               "\"remove_obstacles\":[\"wall\",\"fence\"]}",
               &m)) {
    CHECK_INT(m.add_plant_count, 2);
    if (m.add_plant_count == 2) {
      CHECK_STR(m.add_plants[0].id, "t9");
      CHECK_INT(m.add_plants[0].species, -1);
      CHECK_STR(m.add_plant_species[0], "oak");
      CHECK_STR(m.add_plant_species[1], "pine");
      CHECK_INT(m.add_plants[0].root_count, 2);
      CHECK(m.add_plants[0].roots[1][0] == 1.5);
      CHECK_INT(m.add_plants[1].root_count, 1);
      CHECK_INT(m.add_plants[0].age, 0);
    }
    CHECK_INT(m.add_obstacle_count, 1);
    if (m.add_obstacle_count == 1) {
      CHECK_STR(m.add_obstacles[0].id, "board");
      CHECK(m.add_obstacles[0].max[2] == 3.1);
    }
    CHECK_INT(m.remove_obstacle_count, 2);
    if (m.remove_obstacle_count == 2) CHECK_STR(m.remove_obstacles[1], "fence");
  }
  sylva_msg_free(&m);
  /* a plant's age in years (a species with years: the daemon checks it) */
  if (PARSE_OK("{\"type\":\"edit\",\"run\":4,\"add_plants\":[{\"id\":\"lime\",\"species\":\"l\","
               "\"roots\":[[0,0,0]],\"age\":12}]}",
               &m) &&
      m.add_plant_count == 1)
    CHECK_INT(m.add_plants[0].age, 12);
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"edit\",\"run\":4,\"add_plants\":[],\"add_obstacles\":[],\"remove_"
               "obstacles\":[]}",
               &m))
    CHECK_INT(m.add_plant_count + m.add_obstacle_count + m.remove_obstacle_count, 0);
  sylva_msg_free(&m);
}

/* fork, get and light with their fields. */
static void test_valid_fork_get_light(void) {
  sylva_msg m;
  if (PARSE_OK("{\"type\":\"fork\",\"run\":7,\"iteration\":0,\"name\":\"branch\"}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_FORK);
    CHECK_INT(m.run, 7);
    CHECK_INT(m.iteration, 0);
    CHECK_STR(m.name, "branch");
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"get\",\"run\":7,\"iteration\":12}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_GET);
    CHECK_INT(m.iteration, 12);
  }
  sylva_msg_free(&m);
  if (PARSE_OK("{\"type\":\"light\",\"run\":7,\"z\":-1.5e-1}", &m)) {
    CHECK_INT(m.type, SYLVA_MSG_LIGHT);
    CHECK(m.z == -0.15);
  }
  sylva_msg_free(&m);
}

/* 255-byte names are fine; every type has a name, and only the types. */
static void test_valid_names(void) {
  sylva_msg m;
  char text[4096], name[300];
  memset(name, 'n', 255);
  name[255] = '\0';
  snprintf(text, sizeof text, "{\"type\":\"fork\",\"run\":1,\"iteration\":3,\"name\":\"%s\"}",
           name);
  if (PARSE_OK(text, &m)) CHECK_INT(strlen(m.name), 255);
  sylva_msg_free(&m);
  for (int t = SYLVA_MSG_HELLO; t <= SYLVA_MSG_SCENARIOS; t++)
    CHECK(sylva_msg_type_name((sylva_msg_type)t) != NULL);
  CHECK_STR(sylva_msg_type_name(SYLVA_MSG_LIGHT), "light");
  CHECK(sylva_msg_type_name((sylva_msg_type)99) == NULL);
  sylva_msg_free(NULL);
}

/* ---- bad messages ---- */

/* The top level is an object with a known type; an id is a short string or number. */
static void test_invalid_type_and_id(void) {
  PARSE_BAD("[]", "(root): expected an object, got an array");
  PARSE_BAD("\"hello\"", "(root): expected an object, got a string");
  PARSE_BAD("null", "(root): expected an object, got null");
  PARSE_BAD("{}", "/type: required");
  PARSE_BAD("{\"type\":3}", "/type: expected a string, got a number");
  PARSE_BAD("{\"type\":\"foo\"}", "/type: unknown message type \"foo\"");
  PARSE_BAD("{\"type\":\"Hello\"}", "/type: unknown message type \"Hello\"");
  PARSE_BAD("{\"type\":\"list\",\"id\":[1]}", "/id: expected a string or a number, got an array");
  PARSE_BAD("{\"type\":\"list\",\"id\":null}", "/id: expected a string or a number, got null");
  PARSE_BAD("{\"type\":\"list\",\"id\":1e400}", "/id: number out of range");
  PARSE_BAD("{\"type\":\"list\",\"id\":true}", "/id: expected a string or a number, got a boolean");
  char id[400], text[512];
  memset(id, 'i', 300);
  id[300] = '\0';
  snprintf(text, sizeof text, "{\"type\":\"list\",\"id\":\"%s\"}", id);
  PARSE_BAD(text, "/id: 302 bytes of JSON; at most 256");
}

/* Unknown keys (with a suggestion for a near miss) and duplicate keys. */
static void test_invalid_keys(void) {
  PARSE_BAD("{\"type\":\"list\",\"run\":1}", "/run: unknown key");
  PARSE_BAD("{\"type\":\"list\",\"typo\":1}", "/typo: unknown key");
  PARSE_BAD("{\"type\":\"hello\",\"tokn\":\"x\"}", "/tokn: unknown key (did you mean \"token\"?)");
  PARSE_BAD("{\"type\":\"list\",\"type\":\"list\"}", "/type: duplicate key");
  PARSE_BAD("{\"type\":\"scenarios\",\"x\":{}}", "/x: unknown key");
}

/* Syntax errors name their line and column. */
static void test_invalid_syntax(void) {
  PARSE_BAD("", "(syntax) line 1, column 1");
  PARSE_BAD("{\"type\":\"list\",}", "(syntax)");
  PARSE_BAD("{\"type\": list}", "(syntax) line 1, column 10");
  PARSE_BAD("{\"type\":\"li\\u0000st\"}", "(syntax)");
  PARSE_BAD("{\"type\":\"list\"} {}", "(syntax)");
  PARSE_BAD("{\"type\":\"list\",\"id\":01}", "leading zero");
  PARSE_BAD("{\"type\":\"list\"\n,\"id\":NaN}", "(syntax) line 2");
  parse_bad_at("{\"type\":\"list\"}\0", 16, "(syntax)", __LINE__);
  PARSE_BAD("{\"type\":\"hello\",\"token\":\"\xff\"}", "invalid UTF-8");
}

/* hello's token is a string. */
static void test_invalid_hello(void) {
  PARSE_BAD("{\"type\":\"hello\",\"token\":5}", "/token: expected a string, got a number");
  PARSE_BAD("{\"type\":\"hello\",\"token\":null}", "/token: expected a string, got null");
}

/* create: a scenario object, a name of 1 to 255 bytes and no control, a boolean start. */
static void test_invalid_create(void) {
  PARSE_BAD("{\"type\":\"create\"}", "/scenario: required");
  PARSE_BAD("{\"type\":\"create\",\"scenario\":[]}", "/scenario: expected an object, got an array");
  PARSE_BAD("{\"type\":\"create\",\"scenario\":{}}", "/scenario/format: required");
  /* what follows the small scenario, and the error */
  static const char *const bad[][2] = {
      {",\"name\":\"\"", "/name: must be 1 to 255 bytes long, got 0"},
      {",\"name\":7", "/name: expected a string, got a number"},
      {",\"name\":\"a\\nb\"", "/name: must not contain control characters (byte 1)"},
      {",\"name\":\"ab\\u007f\"", "/name: must not contain control characters (byte 2)"},
      {",\"name\":\"\\u0085\"", "/name: must not contain control characters (byte 0)"},
      {",\"start\":1", "/start: expected a boolean, got a number"},
      {",\"start\":\"true\"", "/start: expected a boolean, got a string"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char text[4096];
    snprintf(text, sizeof text, "{\"type\":\"create\",\"scenario\":%s%s}", small_scenario,
             bad[i][0]);
    PARSE_BAD(text, bad[i][1]);
  }
}

/* create: the scenario's own errors, with pointers into it. */
static void test_invalid_create_scenario(void) {
  PARSE_BAD(
      "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
      "1\",\"world\":{\"min\":[0,0,0],"
      "\"max\":[1,1,1]},\"species\":{\"oak\":{}},\"plants\":[{\"id\":\"t\",\"species\":\"oak\","
      "\"roots\":[[0,0]]}]}}",
      "/scenario/plants/0/roots/0: expected [x, y, z]");
  PARSE_BAD(
      "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
      "1\",\"world\":{\"min\":[0,0,0],"
      "\"max\":[1,0,1]}}}",
      "/scenario/world/max: must be greater than /scenario/world/min on every axis (y: 0 <= 0)");
  PARSE_BAD(
      "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
      "1\",\"world\":{\"min\":[0,0,0],"
      "\"max\":[1,1,1]},\"plants\":[{\"id\":\"t\",\"species\":\"fir\",\"roots\":[[0,0,0]]}]}}",
      "/scenario/plants/0/species: unknown species \"fir\" (not a key of /scenario/species)");
  PARSE_BAD(
      "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
      "1\",\"world\":{\"min\":[0,0,0],"
      "\"max\":[1,1,1]},\"species\":{\"oak\":{}},\"plants\":[{\"id\":\"t\",\"species\":\"oak\","
      "\"roots\":[[0,0,0]]},{\"id\":\"t\",\"species\":\"oak\",\"roots\":[[0.5,0,0]]}]}}",
      "/scenario/plants/1/id: duplicate plant id \"t\" (also /scenario/plants/0/id)");
  PARSE_BAD(
      "{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
      "1\",\"world\":{\"min\":[0,0,0],"
      "\"max\":[1,1,1]},\"obstacles\":[{\"id\":\"w\",\"kind\":\"box\",\"min\":[0,0,0],\"max\":[1,1,"
      "1]},"
      "{\"id\":\"w\",\"kind\":\"box\",\"min\":[0,0,0],\"max\":[1,1,1]}]}}",
      "/scenario/obstacles/1/id: duplicate obstacle id \"w\" (also /scenario/obstacles/0/id)");
  PARSE_BAD("{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/"
            "1\",\"world\":{\"min\":[0,0,0],"
            "\"max\":[100000,100000,100],\"voxel\":0.01}}}",
            "/scenario/world: ");
  PARSE_BAD("{\"type\":\"create\",\"scenario\":{\"format\":\"sylva.scenario/1\",\"seed\":2e400,"
            "\"world\":{\"min\":[0,0,0],\"max\":[1,1,1]}}}",
            "/scenario/seed: number out of range");
}

/* Every type that has a run: required, an integer in [1, 2^53 - 1]; no other key. */
static void test_invalid_run(void) {
  static const char *const with_run[] = {"subscribe", "unsubscribe", "control", "edit",
                                         "fork",      "get",         "light"};
  /* what follows the type, and the error */
  static const char *const bad[][2] = {
      {"", "/run: required"},
      {",\"run\":0", "/run: expected an integer >= 1, got 0"},
      {",\"run\":-3", "/run: expected an integer >= 1, got -3"},
      {",\"run\":1.5", "/run: expected an integer >= 1, got 1.5"},
      {",\"run\":\"1\"", "/run: expected an integer >= 1, got a string"},
      {",\"run\":1e400", "/run: expected an integer >= 1, got a number out of range"},
      {",\"run\":-1e400", "/run: expected an integer >= 1, got a number out of range"},
      {",\"run\":9223372036854775808", "/run: expected an integer >= 1 and <= 9007199254740991 "
                                       "(2^53 - 1), got 9.223372036854776e+18"},
      {",\"run\":9007199254740993", "(2^53 - 1), got 9007199254740992"},
      {",\"run\":1,\"bogus\":1", "/bogus: unknown key"},
      {",\"run\":1"
       "0000000000000000000000000000000000000000000000000000000000000000000",
       "(syntax) line 1, column"},
  };
  for (size_t i = 0; i < sizeof with_run / sizeof with_run[0]; i++)
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
      char text[256];
      snprintf(text, sizeof text, "{\"type\":\"%s\"%s}", with_run[i], bad[k][0]);
      PARSE_BAD(text, bad[k][1]);
    }
}

/* subscribe: since is an integer in [0, 2^53 - 1]. */
static void test_invalid_subscribe(void) {
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"since\":-1}",
            "/since: must be in [0, 9007199254740991], got -1");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"since\":0.5}",
            "/since: must be an integer, got 0.5");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"since\":null}",
            "/since: expected a number, got null");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"since\":1e308}",
            "/since: must be in [0, 9007199254740991]");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"detail\":\"leaves\"}",
            "/detail: unknown detail \"leaves\" (known: nodes, stems)");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"detail\":\"Stems\"}",
            "/detail: unknown detail \"Stems\"");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"detail\":1}",
            "/detail: expected a string, got a number");
  PARSE_BAD("{\"type\":\"subscribe\",\"run\":1,\"detail\":null}",
            "/detail: expected a string, got null");
}

/* control: a known action; a count in [1, 100000], for step only. */
static void test_invalid_control(void) {
  PARSE_BAD("{\"type\":\"control\",\"run\":1}", "/action: required");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"go\"}", "/action: unknown action \"go\"");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":1}",
            "/action: expected a string, got a number");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"step\",\"count\":0}",
            "/count: must be in [1, 100000], got 0");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"step\",\"count\":100001}",
            "/count: must be in [1, 100000], got 100001");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"step\",\"count\":2.5}",
            "/count: must be an integer, got 2.5");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"step\",\"count\":\"2\"}",
            "/count: expected a number, got a string");
  PARSE_BAD("{\"type\":\"control\",\"run\":1,\"action\":\"start\",\"count\":2}",
            "/count: only allowed with \"action\": \"step\"");
}

/* edit's add_plants: unique ids, a species and at least one [x, y, z] root each. */
static void test_invalid_edit_plants(void) {
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":{}}",
            "/add_plants: expected an array, got an object");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[1]}",
            "/add_plants/0: expected an object, got a number");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"oak\"}]}",
            "/add_plants/0/roots: required");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"oak\","
            "\"roots\":[[0,0,0]],\"x\":1}]}",
            "/add_plants/0/x: unknown key");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"oak\","
            "\"roots\":[]}]}",
            "/add_plants/0/roots: must hold at least one root");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"oak\","
            "\"roots\":[[0,0,0],[0,\"1\",0]]}]}",
            "/add_plants/0/roots/1/1: expected a number, got a string");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"oak\","
            "\"roots\":[[0,0,1e999]]}]}",
            "/add_plants/0/roots/0/2: number out of range");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"\",\"species\":\"oak\","
            "\"roots\":[[0,0,0]]}]}",
            "/add_plants/0/id: must be 1 to 63 bytes long, got 0");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"\",\"roots\":"
            "[[0,0,0]]}]}",
            "/add_plants/0/species: must be 1 to 63 bytes long, got 0");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":3,\"roots\":[["
            "0,0,0]]}]}",
            "/add_plants/0/species: expected a string, got a number");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[0,0,0]]},"
            "{\"id\":\"b\",\"species\":\"o\",\"roots\":[[1,0,0]]},{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[2,0,0]]}]}",
            "/add_plants/2/id: duplicate plant id \"a\" (also /add_plants/0/id)");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[0,0,0]],\"age\":501}]}",
            "/add_plants/0/age: must be in [0, 500], got 501");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[0,0,0]],\"age\":-2}]}",
            "/add_plants/0/age: must be in [0, 500], got -2");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[0,0,0]],\"age\":2.5}]}",
            "/add_plants/0/age: must be an integer, got 2.5");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
            "\"roots\":[[0,0,0]],\"age\":\"3\"}]}",
            "/add_plants/0/age: expected a number, got a string");
}

/* edit's add_obstacles: boxes, max above min, unique ids; remove_obstacles: unique ids. */
static void test_invalid_edit_obstacles(void) {
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_obstacles\":[{\"id\":\"w\",\"kind\":\"sphere\","
            "\"min\":[0,0,0],\"max\":[1,1,1]}]}",
            "/add_obstacles/0/kind: unknown obstacle kind \"sphere\"");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_obstacles\":[{\"id\":\"w\",\"kind\":\"box\","
            "\"min\":[0,0,0],\"max\":[1,0,1]}]}",
            "/add_obstacles/0/max: must be greater than min on every axis (y: 0 <= 0)");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_obstacles\":[{\"id\":\"w\",\"min\":[0,0,0],\"max\":"
            "[1,1,1]}]}",
            "/add_obstacles/0/kind: required");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_obstacles\":[{\"id\":\"w\",\"kind\":\"box\","
            "\"min\":[0,0,0],\"max\":[1,1,1]},"
            "{\"id\":\"w\",\"kind\":\"box\",\"min\":[0,0,0],\"max\":[1,1,1]}]}",
            "/add_obstacles/1/id: duplicate obstacle id \"w\" (also /add_obstacles/0/id)");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"add_obstacles\":\"w\"}",
            "/add_obstacles: expected an array, got a string");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"remove_obstacles\":[\"a\",2]}",
            "/remove_obstacles/1: expected a string, got a number");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"remove_obstacles\":[\"\"]}",
            "/remove_obstacles/0: must be 1 to 63 bytes long, got 0");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"remove_obstacles\":[\"a\",\"b\",\"a\"]}",
            "/remove_obstacles/2: duplicate obstacle id \"a\" (also /remove_obstacles/0)");
  PARSE_BAD("{\"type\":\"edit\",\"run\":1,\"remove_obstacles\":\"a\"}",
            "/remove_obstacles: expected an array, got a string");
}

/* Each of edit's lists holds at most 1000 elements. */
static void test_invalid_edit_list_sizes(void) {
  static const char *const lists[] = {"add_plants", "add_obstacles", "remove_obstacles"};
  static const char *const elements[] = {
      "{\"id\":\"p\",\"species\":\"o\",\"roots\":[[0,0,0]]}",
      "{\"id\":\"o\",\"kind\":\"box\",\"min\":[0,0,0],\"max\":[1,1,1]}", "\"x\""};
  for (int l = 0; l < 3; l++) {
    size_t cap = 1001 * 64 + 256, n = 0;
    char *big = malloc(cap);
    if (!big) continue;
    n += (size_t)snprintf(big + n, cap - n, "{\"type\":\"edit\",\"run\":1,\"%s\":[", lists[l]);
    for (int i = 0; i < 1001; i++)
      n += (size_t)snprintf(big + n, cap - n, "%s%s", i ? "," : "", elements[l]);
    snprintf(big + n, cap - n, "]}");
    char want[80];
    snprintf(want, sizeof want, "/%s: 1001 elements; at most 1000", lists[l]);
    PARSE_BAD(big, want);
    free(big);
  }
}

/* fork: an iteration in [0, 2^31 - 1], a name of 1 to 255 bytes and no control. */
static void test_invalid_fork(void) {
  PARSE_BAD("{\"type\":\"fork\",\"run\":1,\"name\":\"x\"}", "/iteration: required");
  PARSE_BAD("{\"type\":\"fork\",\"run\":1,\"iteration\":2}", "/name: required");
  PARSE_BAD("{\"type\":\"fork\",\"run\":1,\"iteration\":-1,\"name\":\"x\"}",
            "/iteration: must be in [0, 2147483647], got -1");
  PARSE_BAD("{\"type\":\"fork\",\"run\":1,\"iteration\":2147483648,\"name\":\"x\"}",
            "/iteration: must be in [0, 2147483647]");
  char name[300], text[512];
  memset(name, 'n', 256);
  name[256] = '\0';
  snprintf(text, sizeof text, "{\"type\":\"fork\",\"run\":1,\"iteration\":3,\"name\":\"%s\"}",
           name);
  PARSE_BAD(text, "/name: must be 1 to 255 bytes long, got 256");
  PARSE_BAD("{\"type\":\"fork\",\"run\":1,\"iteration\":3,\"name\":\"\\t\"}",
            "/name: must not contain control characters");
}

/* get: an integer iteration and nothing else; light: a finite number z. */
static void test_invalid_get_light(void) {
  PARSE_BAD("{\"type\":\"get\",\"run\":1}", "/iteration: required");
  PARSE_BAD("{\"type\":\"get\",\"run\":1,\"iteration\":\"3\"}",
            "/iteration: expected a number, got a string");
  PARSE_BAD("{\"type\":\"get\",\"run\":1,\"iteration\":1.5}",
            "/iteration: must be an integer, got 1.5");
  PARSE_BAD("{\"type\":\"get\",\"run\":1,\"iteration\":1,\"z\":1}", "/z: unknown key");
  PARSE_BAD("{\"type\":\"light\",\"run\":1}", "/z: required");
  PARSE_BAD("{\"type\":\"light\",\"run\":1,\"z\":\"1\"}", "/z: expected a number, got a string");
  PARSE_BAD("{\"type\":\"light\",\"run\":1,\"z\":1e400}", "/z: number out of range");
  PARSE_BAD("{\"type\":\"light\",\"run\":1,\"z\":-1e400}", "/z: number out of range");
  PARSE_BAD("{\"type\":\"light\",\"run\":1,\"z\":[1]}", "/z: expected a number, got an array");
}

/* A bad edit whose second plant's root is not [x, y, z]. */
static const char *const bad_edit =
    "{\"id\":\"r1\",\"type\":\"edit\",\"run\":1,\"add_plants\":[{\"id\":\"a\",\"species\":\"o\","
    "\"roots\":[[0,0,0]]},{\"id\":\"b\",\"species\":\"o\",\"roots\":[[0,0]]}]}";

/* The ref survives a failure so that the error can echo it; nothing else does. */
static void test_invalid_keeps_ref(void) {
  sylva_msg m;
  char err[256];
  CHECK_INT(sylva_msg_parse(bad_edit, strlen(bad_edit), &m, err, sizeof err), SYLVA_EINVAL);
  CHECK_STR(m.ref, "\"r1\"");
  CHECK(m.add_plants == NULL && m.add_plant_count == 0 && m.add_plant_species == NULL);
  CHECK(strstr(err, "/add_plants/1/roots/0: expected [x, y, z]") != NULL);
  sylva_msg_free(&m);
  CHECK(m.ref == NULL);
}

/* The error buffer may be NULL, or short: the message is then cut and NUL-terminated. */
static void test_invalid_error_buffer(void) {
  sylva_msg m;
  CHECK_INT(sylva_msg_parse(bad_edit, strlen(bad_edit), &m, NULL, 0), SYLVA_EINVAL);
  sylva_msg_free(&m);
  CHECK_INT(sylva_msg_parse("[", 1, &m, NULL, 0), SYLVA_EINVAL);
  sylva_msg_free(&m);
  char tiny[8];
  CHECK_INT(sylva_msg_parse(bad_edit, strlen(bad_edit), &m, tiny, sizeof tiny), SYLVA_EINVAL);
  CHECK_INT(strlen(tiny), 7);
  sylva_msg_free(&m);
}

/* A key so long that the pointer is cut stays valid UTF-8 in the message. */
static void test_invalid_long_key(void) {
  char text[8192];
  size_t n = 0;
  n += (size_t)snprintf(text + n, sizeof text - n, "{\"type\":\"list\",\"");
  for (int i = 0; i < 700; i++) n += (size_t)snprintf(text + n, sizeof text - n, "\xc3\xa9");
  snprintf(text + n, sizeof text - n, "\":1}");
  sylva_msg m;
  char err[2048];
  CHECK_INT(sylva_msg_parse(text, strlen(text), &m, err, sizeof err), SYLVA_EINVAL);
  char quoted[2200];
  snprintf(quoted, sizeof quoted, "\"%s\"", err);
  CHECK_INT(sylva_json_check(quoted, strlen(quoted), 1, NULL, 0), 0);
  sylva_msg_free(&m);
}

/* Deep nesting: 64 levels pass the syntax check, 65 do not. */
static void test_depth(void) {
  char text[1024];
  for (int depth = 63; depth <= 66; depth++) {
    size_t n = (size_t)snprintf(text, sizeof text, "{\"type\":\"list\",\"x\":");
    for (int i = 1; i < depth; i++) text[n++] = '[';
    for (int i = 1; i < depth; i++) text[n++] = ']';
    snprintf(text + n, sizeof text - n, "}");
    PARSE_BAD(text, depth <= 64 ? "/x: unknown key" : "(syntax) line 1, column");
  }
  size_t n = 0;
  for (int i = 0; i < 100000 && n + 2 < sizeof text; i++) text[n++] = '[';
  text[n] = '\0';
  PARSE_BAD(text, "nesting deeper than 64");
  /* very deep, far past the limit: no stack trouble */
  size_t big = 2000000;
  char *deep = malloc(big + 1);
  if (deep) {
    memset(deep, '[', big / 2);
    memset(deep + big / 2, ']', big / 2);
    deep[big] = '\0';
    PARSE_BAD(deep, "nesting deeper than 64");
    free(deep);
  }
}

/* ---- JSONTestSuite, raw and wrapped ---- */

static const char *suite_dir;

/* Calls check(name, data, len) for every JSONTestSuite file; returns their number. */
static size_t each_suite_file(void (*check)(const char *name, const char *data, size_t len)) {
  size_t count;
  char **names = list_dir(suite_dir, list_dir_json, &count);
  if (!names) {
    check_failed++;
    fprintf(stderr, "cannot list the JSONTestSuite directory %s\n", suite_dir);
    return 0;
  }
  CHECK(count >= 300);
  for (size_t f = 0; f < count; f++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", suite_dir, names[f]);
    size_t len = 0;
    char *data = read_file(path, &len);
    if (!data) {
      check_failed++;
      fprintf(stderr, "cannot read %s\n", path);
      continue;
    }
    check(names[f], data, len);
    free(data);
  }
  list_dir_free(names, count);
  return count;
}

static size_t raw_errors;

static void check_raw(const char *name, const char *data, size_t len) {
  sylva_msg m;
  char err[512];
  int rc = sylva_msg_parse(data, len, &m, err, sizeof err);
  if (rc == SYLVA_EINVAL && err[0]) {
    raw_errors++;
  } else {
    check_failed++;
    fprintf(stderr, "JSONTestSuite %s raw: expected an error, got %d\n", name, rc);
  }
  sylva_msg_free(&m);
}

/* No file of the suite is a message: each one is an error with its text. */
static void test_suite_raw(void) {
  size_t count = each_suite_file(check_raw);
  CHECK_INT(raw_errors, count);
}

/* Each file as the value of a field of a message (the first two must be refused). */
static const char *const wraps[][2] = {
    {"{\"type\":\"create\",\"id\":7,\"scenario\":", "}"},
    {"{\"type\":\"list\",\"id\":7,\"x\":", "}"},
    {"{\"type\":\"edit\",\"id\":7,\"run\":1,\"add_plants\":", "}"},
    {"{\"type\":\"edit\",\"id\":7,\"run\":1,\"add_obstacles\":[", "]}"},
    {"{\"type\":\"edit\",\"id\":7,\"run\":1,\"remove_obstacles\":", "}"},
    {"{\"type\":\"hello\",\"id\":7,\"token\":", "}"},
    {"{\"type\":\"light\",\"id\":7,\"run\":1,\"z\":", "}"},
    {"{\"type\":\"control\",\"id\":7,\"run\":1,\"action\":\"step\",\"count\":", "}"},
    {"{\"type\":\"list\",\"id\":", "}"},
};
#define WRAPS (sizeof wraps / sizeof wraps[0])
static size_t wrapped_runs;

/* An accepted message has no error text; a rejected one has, and a rejected message
 * that is well-formed JSON still carries the ref 7 (the last wrap makes the file the
 * id itself). */
static void check_wrapped(const char *name, const char *data, size_t len) {
  for (size_t w = 0; w < WRAPS; w++) {
    size_t n1 = strlen(wraps[w][0]), n2 = strlen(wraps[w][1]);
    char *text = malloc(n1 + len + n2 + 1);
    if (!text) continue;
    memcpy(text, wraps[w][0], n1);
    memcpy(text + n1, data, len);
    memcpy(text + n1 + len, wraps[w][1], n2);
    text[n1 + len + n2] = '\0';
    sylva_msg m;
    char err[512];
    int rc = sylva_msg_parse(text, n1 + len + n2, &m, err, sizeof err);
    wrapped_runs++;
    bool valid_json = sylva_json_check_ex(text, n1 + len + n2, 64,
                                          SYLVA_JSON_NO_NUL_ESCAPE | SYLVA_JSON_CJSON_NUMBERS,
                                          NULL, 0) == 0;
    if (rc == 0) {
      if (w < 2) {
        check_failed++;
        fprintf(stderr, "JSONTestSuite %s in wrap %zu: accepted\n", name, w);
      }
    } else if (rc != SYLVA_EINVAL || !err[0]) {
      check_failed++;
      fprintf(stderr, "JSONTestSuite %s in wrap %zu: status %d\n", name, w, rc);
    } else if (valid_json && w + 1 < WRAPS && !(m.ref && strcmp(m.ref, "7") == 0)) {
      check_failed++;
      fprintf(stderr, "JSONTestSuite %s in wrap %zu: ref lost (%s)\n", name, w, err);
    }
    sylva_msg_free(&m);
    free(text);
  }
}

/* Each file wrapped into every message: refused where it must be, the ref kept. */
static void test_suite_wrapped(void) {
  size_t count = each_suite_file(check_wrapped);
  CHECK_INT(wrapped_runs, count * WRAPS);
}

/* ---- encoders ---- */

/* The encoder's text is exactly want and valid JSON; frees it. */
static void check_encoded(char *text, const char *want) {
  CHECK_STR(text, want);
  cJSON_Delete(VALID_JSON(text));
  free(text);
}

/* welcome: protocol, server, auth and public_read for each token rule, and the
 * ref when given. */
static void test_encode_welcome(void) {
  check_encoded(sylva_msg_welcome("0.1.0", SYLVA_AUTH_ALL, NULL),
                "{\"type\":\"welcome\",\"protocol\":1,\"server\":{\"name\":\"sylva\",\"version\":"
                "\"0.1.0\"},\"auth\":true,\"public_read\":false}");
  check_encoded(sylva_msg_welcome("0.1.0", SYLVA_AUTH_CHANGES, NULL),
                "{\"type\":\"welcome\",\"protocol\":1,\"server\":{\"name\":\"sylva\",\"version\":"
                "\"0.1.0\"},\"auth\":true,\"public_read\":true}");
  check_encoded(sylva_msg_welcome("0.1.0", SYLVA_AUTH_NONE, "\"h1\""),
                "{\"type\":\"welcome\",\"protocol\":1,\"server\":{\"name\":\"sylva\",\"version\":"
                "\"0.1.0\"},\"auth\":false,\"public_read\":true,\"ref\":\"h1\"}");
  char *text = sylva_msg_welcome(NULL, SYLVA_AUTH_NONE, NULL);
  cJSON *j = VALID_JSON(text);
  if (j) {
    CHECK(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(j, "auth")));
    CHECK_INT(num_of(j, "protocol"), 1);
  }
  cJSON_Delete(j);
  free(text);
}

/* error: every code; the message escaped, cut UTF-8 replaced; the ref when given. */
static void test_encode_error(void) {
  static const char *const codes[] = {"bad_request", "unknown_run", "unauthorized",
                                      "too_large",   "busy",        "internal"};
  for (size_t i = 0; i < 6; i++) {
    char *text = sylva_msg_error(codes[i], "/run: expected an integer >= 1, got \"x\"\n\t\x01",
                                 i % 2 ? "\"r\\\"1\"" : NULL);
    cJSON *j = VALID_JSON(text);
    if (j) {
      CHECK_STR(str_of(j, "type"), "error");
      CHECK_STR(str_of(j, "code"), codes[i]);
      CHECK_STR(str_of(j, "message"), "/run: expected an integer >= 1, got \"x\"\n\t\x01");
      if (i % 2) CHECK_STR(str_of(j, "ref"), "r\"1");
      else CHECK(cJSON_GetObjectItemCaseSensitive(j, "ref") == NULL);
    }
    cJSON_Delete(j);
    free(text);
  }
  check_encoded(sylva_msg_error("bad_request", "cut \xc3", "12"),
                "{\"type\":\"error\",\"code\":\"bad_request\",\"message\":\"cut \\ufffd\","
                "\"ref\":12}");
}

/* A parse error echoed through the encoder is valid JSON, with the ref decoded. */
static void test_encode_parse_error(void) {
  sylva_msg m;
  char err[512];
  const char *bad = "{\"id\":\"\\u00e9\\ud83c\\udf33\",\"type\":\"nope\\u00e9\"}";
  CHECK_INT(sylva_msg_parse(bad, strlen(bad), &m, err, sizeof err), SYLVA_EINVAL);
  char *text = sylva_msg_error("bad_request", err, m.ref);
  cJSON *j = VALID_JSON(text);
  if (j) {
    CHECK_STR(str_of(j, "ref"), "\xc3\xa9\xf0\x9f\x8c\xb3");
    CHECK(strstr(str_of(j, "message") ? str_of(j, "message") : "", "unknown message type") !=
          NULL);
  }
  cJSON_Delete(j);
  free(text);
  sylva_msg_free(&m);
}

/* created: the run and its name, escaped. */
static void test_encode_created(void) {
  check_encoded(sylva_msg_created(3, "oak \"stand\"", "\"c\""),
                "{\"type\":\"created\",\"run\":3,\"name\":\"oak \\\"stand\\\"\",\"ref\":\"c\"}");
}

/* status: runs beyond 2^53, each status by its one name (run_status.h), parsed back. */
static void test_encode_status(void) {
  check_encoded(
      sylva_msg_status(9007199254740992LL, SYLVA_RUN_PAUSED, 12, 0, NULL),
      "{\"type\":\"status\",\"run\":9007199254740992,\"status\":\"paused\",\"iteration\":12}");
  static const char *const statuses[] = {"paused", "running", "finished", "failed"};
  for (int i = 0; i < 4; i++) {
    sylva_run_status parsed;
    CHECK_INT(sylva_run_status_parse(statuses[i], &parsed), 0);
    CHECK_INT(parsed, i);
    char *text = sylva_msg_status(2, (sylva_run_status)i, i, 0, "5");
    cJSON *j = VALID_JSON(text);
    if (j) {
      CHECK_STR(str_of(j, "status"), statuses[i]);
      CHECK_INT(num_of(j, "iteration"), i);
      CHECK_INT(num_of(j, "ref"), 5);
    }
    cJSON_Delete(j);
    free(text);
  }
  /* a run with a start year says it */
  check_encoded(sylva_msg_status(2, SYLVA_RUN_RUNNING, 5, 2027, "\"s\""),
                "{\"type\":\"status\",\"run\":2,\"status\":\"running\",\"iteration\":5,"
                "\"start_year\":2027,\"ref\":\"s\"}");
  sylva_run_status none;
  CHECK_INT(sylva_run_status_parse("stopped", &none), -1);
  CHECK_STR(sylva_run_status_name((sylva_run_status)99), "unknown");
}

/* runs, and the same list alone: names escaped (a missing one empty), big node counts. */
static void test_encode_runs(void) {
  sylva_run_summary runs[] = {
      {1, "wall", SYLVA_RUN_RUNNING, 4, 5, 1234, false, NULL, 0, NULL},
      {2, "tab\there \xe2\x9c\x93", SYLVA_RUN_FINISHED, 40, 1, 9000000000LL, false, NULL, 0, NULL},
      {3, NULL, SYLVA_RUN_PAUSED, 0, 0, 0, true, NULL, 0, NULL},
  };
  char *text = sylva_msg_runs(runs, 3, "\"L\"");
  cJSON *j = VALID_JSON(text);
  if (j) {
    CHECK_STR(str_of(j, "type"), "runs");
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(j, "runs");
    CHECK_INT(cJSON_GetArraySize(arr), 3);
    const cJSON *r1 = cJSON_GetArrayItem(arr, 1);
    CHECK_STR(str_of(r1, "name"), "tab\there \xe2\x9c\x93");
    CHECK(num_of(r1, "nodes") == 9000000000.0);
    CHECK_STR(str_of(cJSON_GetArrayItem(arr, 2), "name"), "");
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(arr, 2), "loading")));
    CHECK(!cJSON_GetObjectItemCaseSensitive(r1, "loading"));
    CHECK_STR(str_of(j, "ref"), "L");
  }
  cJSON_Delete(j);
  free(text);
  text = sylva_msg_runs(runs, 1, NULL);
  CHECK_STR(text, "{\"type\":\"runs\",\"runs\":[{\"run\":1,\"name\":\"wall\",\"status\":"
                  "\"running\",\"iteration\":4,\"stems\":5,\"nodes\":1234}]}");
  free(text);
  text = sylva_runs_json(runs, 1);
  CHECK_STR(text, "[{\"run\":1,\"name\":\"wall\",\"status\":\"running\",\"iteration\":4,\"stems\":"
                  "5,\"nodes\":1234}]");
  free(text);
  text = sylva_runs_json(NULL, 0);
  CHECK_STR(text, "[]");
  free(text);
  text = sylva_msg_runs(NULL, 0, NULL);
  CHECK_STR(text, "{\"type\":\"runs\",\"runs\":[]}");
  free(text);
}

/* runs of a sweep: their sweep, position and axes after the other fields, the axes
 * written again member by member (escaped; a member that is not a string, or a text
 * that is not an object, left out). */
static void test_encode_sweep_runs(void) {
  sylva_run_summary runs[] = {
      {1, "a", SYLVA_RUN_FINISHED, 10, 5, 70, false, "street \"species\"", 1,
       "{\"species/street-tree\":\"utdb:NoEast:GIBI\",\"seed\":\"1\",\"variant\":\"as built\"}"},
      {2, "b", SYLVA_RUN_PAUSED, 0, 1, 3, false, "s", 0,
       "{\"seed\":\"2\",\"n\":3,\"tab\":\"a\\tb\"}"},
      {3, "c", SYLVA_RUN_PAUSED, 0, 1, 3, false, "s", 2, "[\"not an object\"]"},
      {4, "d", SYLVA_RUN_PAUSED, 0, 1, 3, false, "s", 3, NULL},
  };
  char *text = sylva_runs_json(runs, 4);
  CHECK_STR(text,
            "[{\"run\":1,\"name\":\"a\",\"status\":\"finished\",\"iteration\":10,\"stems\":5,"
            "\"nodes\":70,\"sweep\":\"street \\\"species\\\"\",\"position\":1,\"axes\":{"
            "\"species/street-tree\":\"utdb:NoEast:GIBI\",\"seed\":\"1\","
            "\"variant\":\"as built\"}},"
            "{\"run\":2,\"name\":\"b\",\"status\":\"paused\",\"iteration\":0,\"stems\":1,"
            "\"nodes\":3,\"sweep\":\"s\",\"position\":0,\"axes\":{\"seed\":\"2\","
            "\"tab\":\"a\\tb\"}},"
            "{\"run\":3,\"name\":\"c\",\"status\":\"paused\",\"iteration\":0,\"stems\":1,"
            "\"nodes\":3,\"sweep\":\"s\",\"position\":2},"
            "{\"run\":4,\"name\":\"d\",\"status\":\"paused\",\"iteration\":0,\"stems\":1,"
            "\"nodes\":3,\"sweep\":\"s\",\"position\":3}]");
  cJSON_Delete(VALID_JSON(text));
  free(text);
}

/* scenarios: the ready scenarios with their titles (the name when there is none). */
static void test_encode_scenarios(void) {
  const char *names[] = {"wall", "urban"};
  const char *titles[] = {"Tree beside a wall", NULL};
  check_encoded(
      sylva_msg_scenarios(names, titles, 2, "1"),
      "{\"type\":\"scenarios\",\"scenarios\":[{\"name\":\"wall\",\"title\":\"Tree beside a wall\"},"
      "{\"name\":\"urban\",\"title\":\"urban\"}],\"ref\":1}");
  char *text = sylva_msg_scenarios(names, NULL, 0, NULL);
  CHECK_STR(text, "{\"type\":\"scenarios\",\"scenarios\":[]}");
  free(text);
}

/* ---- snapshot + deltas = skeleton ---- */

typedef struct model_node {
  bool live;
  double parent, plant, stem, x, y, z, r, birth;
  double leaves; /* the leaves the messages gave it (0 when none) */
} model_node;

typedef struct model {
  model_node *nodes;
  size_t cap;
} model;

static model_node *model_at(model *m, double id) {
  if (!(id >= 0) || id > 1e8 || id != floor(id)) return NULL;
  size_t i = (size_t)id;
  if (i >= m->cap) {
    size_t cap = m->cap ? m->cap : 1024;
    while (cap <= i) cap *= 2;
    model_node *bigger = realloc(m->nodes, cap * sizeof *bigger);
    if (!bigger) return NULL;
    memset(bigger + m->cap, 0, (cap - m->cap) * sizeof *bigger);
    m->nodes = bigger;
    m->cap = cap;
  }
  return &m->nodes[i];
}

static double item_num(const cJSON *arr, int i) {
  const cJSON *e = cJSON_GetArrayItem(arr, i);
  return cJSON_IsNumber(e) ? e->valuedouble : NAN;
}

/* Node lists of a skeleton-shaped tree ("plants": [{"stems": [{"nodes": ...}]}])
 * into the model. */
static void model_load(model *m, const cJSON *root) {
  const cJSON *plants = cJSON_GetObjectItemCaseSensitive(root, "plants");
  int p = 0;
  for (const cJSON *pl = plants ? plants->child : NULL; pl; pl = pl->next, p++) {
    int k = 0;
    const cJSON *stems = cJSON_GetObjectItemCaseSensitive(pl, "stems");
    for (const cJSON *st = stems ? stems->child : NULL; st; st = st->next, k++) {
      const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(st, "nodes");
      for (const cJSON *n = nodes ? nodes->child : NULL; n; n = n->next) {
        model_node *mn = model_at(m, item_num(n, 0));
        if (!mn) {
          check_failed++;
          continue;
        }
        *mn = (model_node){true, item_num(n, 1), p, k, item_num(n, 2), item_num(n, 3),
                           item_num(n, 4), item_num(n, 5), item_num(n, 6), 0};
      }
    }
  }
}

/* Sets the leaves of a "leaves" list ([[id, n], ...], ids ascending) on live nodes. */
static void model_set_leaves(model *m, const cJSON *leaves) {
  CHECK(cJSON_IsArray(leaves));
  double last = -1;
  for (const cJSON *e = leaves ? leaves->child : NULL; e; e = e->next) {
    CHECK_INT(cJSON_GetArraySize(e), 2);
    double id = item_num(e, 0), n = item_num(e, 1);
    CHECK(id > last && n >= 0 && n == floor(n));
    last = id;
    model_node *mn = model_at(m, id);
    CHECK(mn && mn->live);
    if (mn) mn->leaves = n;
  }
}

/* A snapshot into the model: its nodes, then its leaves (every entry above 0). */
static void model_load_snapshot(model *m, const cJSON *snap) {
  model_load(m, snap);
  const cJSON *leaves = cJSON_GetObjectItemCaseSensitive(snap, "leaves");
  for (const cJSON *e = leaves ? leaves->child : NULL; e; e = e->next) CHECK(item_num(e, 1) > 0);
  model_set_leaves(m, leaves);
}

/* Applies one delta; returns the number of shed subtree roots. */
static size_t model_apply(model *m, const cJSON *delta) {
  double iteration = num_of(delta, "iteration");
  const cJSON *added = cJSON_GetObjectItemCaseSensitive(delta, "added");
  for (const cJSON *n = added ? added->child : NULL; n; n = n->next) {
    CHECK_INT(cJSON_GetArraySize(n), 8);
    model_node *mn = model_at(m, item_num(n, 0));
    if (!mn) {
      check_failed++;
      continue;
    }
    CHECK(!mn->live);
    double parent = item_num(n, 1);
    model_node *pn = parent >= 0 ? model_at(m, parent) : NULL;
    CHECK(parent == -1 || (pn && pn->live));
    *mn = (model_node){true, parent, item_num(n, 2), item_num(n, 3), item_num(n, 4),
                       item_num(n, 5), item_num(n, 6), item_num(n, 7), iteration, 0};
  }
  const cJSON *radii = cJSON_GetObjectItemCaseSensitive(delta, "radii");
  for (const cJSON *r = radii ? radii->child : NULL; r; r = r->next) {
    CHECK_INT(cJSON_GetArraySize(r), 2);
    model_node *mn = model_at(m, item_num(r, 0));
    CHECK(mn && mn->live);
    if (mn) mn->r = item_num(r, 1);
  }
  const cJSON *shed = cJSON_GetObjectItemCaseSensitive(delta, "shed");
  size_t shed_count = 0;
  bool *dead = calloc(m->cap ? m->cap : 1, sizeof *dead);
  if (!dead) return 0;
  for (const cJSON *s = shed ? shed->child : NULL; s; s = s->next) {
    model_node *mn = model_at(m, s->valuedouble);
    if (mn && mn->live) dead[(size_t)s->valuedouble] = true;
    shed_count++;
  }
  /* Subtrees, until nothing changes (no assumption on the id order). */
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 0; i < m->cap; i++) {
      model_node *mn = &m->nodes[i];
      if (!mn->live || dead[i] || mn->parent < 0 || (size_t)mn->parent >= m->cap) continue;
      if (dead[(size_t)mn->parent]) dead[i] = changed = true;
    }
  }
  for (size_t i = 0; i < m->cap; i++)
    if (dead[i]) m->nodes[i].live = false;
  free(dead);
  model_set_leaves(m, cJSON_GetObjectItemCaseSensitive(delta, "leaves"));
  return shed_count;
}

/* The model's leaves must be those the world gives every node
 * (sylva_node_info.leaves). Returns the leaves counted. */
static int64_t model_compare_leaves(model *m, const sylva_world *w, int iteration) {
  size_t bad = 0, count = sylva_world_node_count(w);
  int64_t total = 0;
  for (size_t i = 0; i < count; i++) {
    sylva_node_info n;
    sylva_world_node_at(w, i, &n);
    total += n.leaves;
    model_node *mn = model_at(m, n.id);
    if (mn && mn->live && mn->leaves == n.leaves) continue;
    if (bad++ < 5)
      fprintf(stderr, "iteration %d: node %d has %d leaves, the messages gave %g\n", iteration,
              (int)n.id, (int)n.leaves, mn ? mn->leaves : -1.0);
  }
  if (bad) check_failed++;
  else check_passed++;
  return total;
}

/* The model must hold exactly the skeleton's nodes. */
static void model_compare(model *m, const cJSON *skeleton, int iteration) {
  size_t live = 0, seen = 0, bad = 0;
  for (size_t i = 0; i < m->cap; i++) live += m->nodes[i].live;
  const cJSON *plants = cJSON_GetObjectItemCaseSensitive(skeleton, "plants");
  int p = 0;
  for (const cJSON *pl = plants ? plants->child : NULL; pl; pl = pl->next, p++) {
    int k = 0;
    const cJSON *stems = cJSON_GetObjectItemCaseSensitive(pl, "stems");
    for (const cJSON *st = stems ? stems->child : NULL; st; st = st->next, k++) {
      const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(st, "nodes");
      for (const cJSON *n = nodes ? nodes->child : NULL; n; n = n->next) {
        seen++;
        double id = item_num(n, 0);
        model_node *mn = id < (double)m->cap ? model_at(m, id) : NULL;
        bool same = mn && mn->live && mn->parent == item_num(n, 1) && mn->plant == p &&
                    mn->stem == k && mn->x == item_num(n, 2) && mn->y == item_num(n, 3) &&
                    mn->z == item_num(n, 4) && mn->r == item_num(n, 5) &&
                    mn->birth == item_num(n, 6);
        if (!same && bad++ < 5) {
          fprintf(stderr,
                  "iteration %d: node %.0f differs: skeleton [%.17g,%.17g,%.17g,%.17g,%.17g,%.17g] "
                  "p%d s%d",
                  iteration, id, item_num(n, 1), item_num(n, 2), item_num(n, 3), item_num(n, 4),
                  item_num(n, 5), item_num(n, 6), p, k);
          if (mn && mn->live)
            fprintf(stderr, ", model [%.17g,%.17g,%.17g,%.17g,%.17g,%.17g] p%.0f s%.0f\n",
                    mn->parent, mn->x, mn->y, mn->z, mn->r, mn->birth, mn->plant, mn->stem);
          else
            fprintf(stderr, ", not in the model\n");
        }
      }
    }
  }
  if (bad || seen != live) {
    check_failed++;
    fprintf(stderr, "iteration %d: %zu nodes differ; skeleton %zu nodes, model %zu\n", iteration,
            bad, seen, live);
  } else {
    check_passed++;
  }
}

/* The text from "\"obstacles\":" up to ",\"stats\"" or the closing "}" of a skeleton. */
static char *obstacles_and_plants(const char *text) {
  const char *from = text ? strstr(text, "\"obstacles\":") : NULL;
  if (!from) return NULL;
  const char *to = strstr(from, ",\"stats\":");
  if (!to) to = strstr(from, "]}\n") ? strstr(from, "]}\n") + 1 : NULL;
  if (!to) return NULL;
  size_t n = (size_t)(to - from);
  char *out = malloc(n + 1);
  if (out) {
    memcpy(out, from, n);
    out[n] = '\0';
  }
  return out;
}

static void check_snapshot_matches_skeleton(const char *snapshot, const sylva_world *w) {
  char *skeleton = sylva_encode_skeleton(w);
  char *a = obstacles_and_plants(snapshot), *b = obstacles_and_plants(skeleton);
  CHECK(a && b && strcmp(a, b) == 0);
  /* and the world part */
  const char *va = snapshot ? strstr(snapshot, "\"voxel\":") : NULL;
  const char *vb = skeleton ? strstr(skeleton, "\"voxel\":") : NULL;
  CHECK(va && vb && a && strncmp(va, vb, (size_t)(strstr(va, "\"obstacles\":") - va)) == 0);
  free(a);
  free(b);
  free(skeleton);
}

/* A default world with one upright species, "oak" (species 0); *sp is its def. */
static sylva_world *oak_world(sylva_species_def *sp) {
  sylva_world_def def = sylva_default_world_def();
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  if (!w) return NULL;
  *sp = sylva_default_species_def();
  sp->tropism[0] = 0, sp->tropism[1] = 0, sp->tropism[2] = 1;
  CHECK_INT(sylva_world_add_species(w, sp, "oak"), 0);
  return w;
}

/* The world of the snapshot tests: a wall, a tree and a two-root shrub of one
 * species, and a species no plant uses yet (still offered; its label needs escaping). */
static sylva_world *snapshot_world(void) {
  sylva_species_def sp;
  sylva_world *w = oak_world(&sp);
  if (!w) return NULL;
  int species = 0;
  CHECK_INT(sylva_world_add_species(w, &sp, "big \"leaf\""), species + 1);
  sylva_obstacle_def wall = {.label = "wall", .min = {1.0, -5, 0}, .max = {1.2, 5, 4}};
  CHECK(sylva_world_add_obstacle(w, &wall) >= 0);
  const double tree_roots[][3] = {{0, 0, 0}};
  const double shrub_roots[][3] = {{-2, -2, 0}, {-2.6, -1.7, 0}};
  sylva_plant_def tree = {species, "t1", tree_roots, 1, 0, NULL, 0};
  sylva_plant_def shrub = {species, "s\"1", shrub_roots, 2, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &tree, NULL), 0);
  CHECK_INT(sylva_world_add_plant(w, &shrub, NULL), 1);
  return w;
}

/* Grows w n iterations. */
static void grow(sylva_world *w, int n) {
  for (int i = 0; i < n; i++) CHECK_INT(sylva_world_step(w, NULL), 0);
}

/* The model must hold exactly the nodes of w's skeleton. */
static void compare_with_skeleton(model *m, const sylva_world *w, int iteration) {
  char *skel = sylva_encode_skeleton(w);
  cJSON *kj = skel ? cJSON_Parse(skel) : NULL;
  CHECK(kj != NULL);
  model_compare(m, kj, iteration);
  cJSON_Delete(kj);
  free(skel);
}

/* A first snapshot: its header, stats and species; nodes, obstacles, plants as the skeleton's. */
/* The stems snapshot of w is its snapshot (full, parsed) with "detail":"stems", no
 * nodes in the stems and no leaves; the nodes snapshot of _detail is the snapshot. */
static void check_stems_snapshot(cJSON *full, const sylva_world *w) {
  char *nodes = sylva_msg_snapshot_detail(4, 10, w, 0, SYLVA_DETAIL_NODES, "\"sub\"");
  char *stems = sylva_msg_snapshot_detail(4, 10, w, 0, SYLVA_DETAIL_STEMS, "\"sub\"");
  cJSON *want = cJSON_Duplicate(full, true), *got = VALID_JSON(stems);
  CHECK(full && nodes && stems && strstr(stems, "\"iteration\":0,\"detail\":\"stems\",\"voxel\""));
  if (want && got) {
    cJSON *full_again = cJSON_Parse(nodes);
    CHECK(cJSON_Compare(full_again, full, true));
    cJSON_Delete(full_again);
    cJSON_DeleteItemFromObjectCaseSensitive(want, "leaves");
    const cJSON *plant = NULL;
    cJSON_ArrayForEach(plant, cJSON_GetObjectItemCaseSensitive(want, "plants")) {
      cJSON *stem = NULL;
      cJSON_ArrayForEach(stem, cJSON_GetObjectItemCaseSensitive(plant, "stems")) {
        CHECK(cJSON_GetObjectItemCaseSensitive(stem, "nodes") != NULL);
        cJSON_DeleteItemFromObjectCaseSensitive(stem, "nodes");
      }
    }
    cJSON_AddStringToObject(want, "detail", "stems");
    CHECK(cJSON_Compare(want, got, true));
  }
  cJSON_Delete(want);
  cJSON_Delete(got);
  free(nodes);
  free(stems);
}

static void test_snapshot(void) {
  sylva_world *w = snapshot_world();
  if (!w) return;
  char *snap = sylva_msg_snapshot(4, 10, w, 0, "\"sub\"");
  cJSON *sj = VALID_JSON(snap);
  model m = {0};
  if (sj) {
    CHECK_STR(str_of(sj, "type"), "snapshot");
    CHECK_INT(num_of(sj, "run"), 4);
    CHECK_INT(num_of(sj, "seq"), 10);
    CHECK_INT(num_of(sj, "iteration"), 0);
    CHECK(num_of(sj, "voxel") == 0.05);
    CHECK_STR(str_of(sj, "ref"), "sub");
    CHECK_INT(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(sj, "stats")), 3);
    CHECK_INT(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(sj, "plants")), 2);
    CHECK_STR(str_of(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(sj, "stats"), 2), "plant"),
              "s\"1");
    /* the species' labels in id order, after the stats (the skeleton part is unchanged) */
    const cJSON *labels = cJSON_GetObjectItemCaseSensitive(sj, "species");
    CHECK_INT(cJSON_GetArraySize(labels), 2);
    CHECK_STR(cJSON_GetStringValue(cJSON_GetArrayItem(labels, 0)), "oak");
    CHECK_STR(cJSON_GetStringValue(cJSON_GetArrayItem(labels, 1)), "big \"leaf\"");
    CHECK(snap && strstr(snap, "],\"species\":[\"oak\",\"big \\\"leaf\\\"\"],\"sky\":\"zenith\",\"foliage\":["));
    /* each species' leaves, then the nodes bearing them, before the ref */
    CHECK(snap && strstr(snap, ",\"foliage\":[{\"species\":\"oak\",\"leaf_size\":0.1,"
                               "\"leaf_density\":6,\"leaf_colour\":\"#4a7f35\"},"
                               "{\"species\":\"big \\\"leaf\\\"\",\"leaf_size\":0.1,"
                               "\"leaf_density\":6,\"leaf_colour\":\"#4a7f35\"}],\"plant_species\":[0,0],"
                               "\"leaves\":[["));
    CHECK(snap && strstr(snap, "]],\"canopy_cover\":"));
    CHECK(snap && strstr(snap, ",\"ref\":\"sub\"}"));
    /* the canopy cover as the world measures it, in [0, 1] */
    double cover = num_of(sj, "canopy_cover");
    CHECK(cover >= 0 && cover <= 1 && fabs(cover - sylva_world_canopy_cover(w)) <= 5e-5);
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(sj, "leaves")) > 0);
    model_load_snapshot(&m, sj);
  }
  check_snapshot_matches_skeleton(snap, w);
  compare_with_skeleton(&m, w, 0);
  model_compare_leaves(&m, w, 0);
  check_stems_snapshot(sj, w);
  cJSON_Delete(sj);
  free(snap);
  free(m.nodes);
  sylva_world_destroy(w);
}

typedef struct delta_totals {
  size_t added, radii, shed, leaves, leafless;
} delta_totals;

/* The delta of iteration it: its header and stats (those of the stats line); applied
 * to the model. */
static void apply_delta(model *m, const sylva_world *w, const sylva_journal *j, int it,
                        delta_totals *t) {
  char *delta = sylva_msg_delta(4, 10 + it, w, j, 0);
  cJSON *dj = VALID_JSON(delta);
  if (dj) {
    CHECK_STR(str_of(dj, "type"), "delta");
    CHECK_INT(num_of(dj, "run"), 4);
    CHECK_INT(num_of(dj, "seq"), 10 + it);
    CHECK_INT(num_of(dj, "iteration"), it);
    CHECK(cJSON_GetObjectItemCaseSensitive(dj, "ref") == NULL);
    t->added += (size_t)cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(dj, "added"));
    t->radii += (size_t)cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(dj, "radii"));
    const cJSON *leaves = cJSON_GetObjectItemCaseSensitive(dj, "leaves");
    CHECK_INT(cJSON_GetArraySize(leaves), (int)j->leaves_count);
    t->leaves += j->leaves_count;
    for (size_t i = 0; i < j->leaves_count; i++) t->leafless += j->leaves[i].leaves == 0;
    t->shed += model_apply(m, dj);
    /* the stems delta: the same stats, canopy cover and stand bytes, without nodes */
    char *stems = sylva_msg_delta_detail(4, 10 + it, w, j, 0, SYLVA_DETAIL_STEMS);
    char *full_again = sylva_msg_delta_detail(4, 10 + it, w, j, 0, SYLVA_DETAIL_NODES);
    char head[128];
    snprintf(head, sizeof head,
             "{\"type\":\"delta\",\"run\":4,\"seq\":%d,\"iteration\":%d,\"detail\":\"stems\",",
             10 + it, it);
    const char *tail = strstr(delta, "\"stats\":[");
    CHECK(stems && tail && strncmp(stems, head, strlen(head)) == 0 &&
          strcmp(stems + strlen(head), tail) == 0);
    CHECK(full_again && strcmp(full_again, delta) == 0);
    free(stems);
    free(full_again);
    char *line = sylva_encode_stats_line(w, j, 0, 0);
    cJSON *lj = line ? cJSON_Parse(line) : NULL;
    CHECK(lj && cJSON_Compare(cJSON_GetObjectItemCaseSensitive(lj, "stems"),
                              cJSON_GetObjectItemCaseSensitive(dj, "stats"), true));
    cJSON_Delete(lj);
    free(line);
  }
  cJSON_Delete(dj);
  free(delta);
}

/* The model of w's snapshot now (its nodes and leaves). */
static model model_of_snapshot(const sylva_world *w) {
  char *snap = sylva_msg_snapshot(4, 10, w, 0, "\"sub\"");
  cJSON *sj = VALID_JSON(snap);
  model m = {0};
  model_load_snapshot(&m, sj);
  cJSON_Delete(sj);
  free(snap);
  return m;
}

/* Grows w through iterations from..to, applying each delta to the model, which must
 * then hold the skeleton and every node's leaves. */
static void step_and_apply(model *m, sylva_world *w, int from, int to, delta_totals *t) {
  for (int it = from; it <= to; it++) {
    const sylva_journal *j = NULL;
    int rc = sylva_world_step(w, &j);
    CHECK_INT(rc, 0);
    if (rc || !j) break;
    apply_delta(m, w, j, it, t);
    compare_with_skeleton(m, w, it);
    model_compare_leaves(m, w, it);
  }
}

/* The first snapshot plus 15 deltas rebuild the skeleton and the leaves after every
 * iteration. */
static void test_deltas(void) {
  sylva_world *w = snapshot_world();
  if (!w) return;
  model m = model_of_snapshot(w);
  delta_totals t = {0};
  step_and_apply(&m, w, 1, 15, &t);
  printf("snapshot + 15 deltas: %zu nodes added, %zu radii, %zu subtrees shed, %zu leaf changes "
         "(%zu lost)\n",
         t.added, t.radii, t.shed, t.leaves, t.leafless);
  CHECK(t.added > 100);
  CHECK(t.radii > 0);
  CHECK(t.leaves > 0 && t.leafless > 0);
  /* each stem's leaf area is its leaves as the messages gave them x pi/4 x size^2 */
  for (int s = 0; s < sylva_world_stem_count(w); s++) {
    sylva_stem_stats st;
    sylva_world_stem_stats(w, s, &st);
    double leaves = 0;
    for (size_t i = 0; i < m.cap; i++) {
      const model_node *mn = &m.nodes[i];
      if (mn->live && sylva_world_stem_index(w, (int)mn->plant, (int)mn->stem) == s)
        leaves += mn->leaves;
    }
    const sylva_species_def *d = sylva_world_species(w, 0);
    double want = leaves * SYLVA_LEAF_FILL * d->leaf_size * d->leaf_size;
    CHECK(st.leaf_area > 0 && fabs(st.leaf_area - want) <= 1e-9 * want);
  }
  free(m.nodes);
  sylva_world_destroy(w);
}

/* Plants added between iterations (as an edit adds them, to a world read back from
 * its image): a snapshot after the addition plus the deltas that follow give every
 * node its leaves, those of a plant planted old (some of whose nodes lose their
 * leaves at the next iteration) and of a species whose nodes bear leaves for one
 * iteration only. */
static void test_leaves_after_edit(void) {
  sylva_species_def sp;
  sylva_world *grown = oak_world(&sp);
  if (!grown) return;
  sp.years = 1;
  int lime = sylva_world_add_species(grown, &sp, "lime");
  sp.years = 0;
  sp.leaf_age = 1;
  sp.leaf_density = 3;
  int brief = sylva_world_add_species(grown, &sp, "brief");
  const double a[][3] = {{-2, 0, 0}};
  sylva_plant_def first = {0, "first", a, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(grown, &first, NULL), 0);
  grow(grown, 4);
  uint8_t *img = NULL;
  size_t size = 0;
  sylva_world *w = NULL;
  CHECK_INT(sylva_snapshot_save(grown, &img, &size), 0);
  CHECK_INT(sylva_snapshot_load(img, size, &w), 0);
  free(img);
  sylva_world_destroy(grown);
  if (!w) return;
  const double b[][3] = {{0, 0, 0}}, c[][3] = {{2, 0, 0}};
  sylva_plant_def old = {lime, "old", b, 1, 6, NULL, 0}, young = {brief, "young", c, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &old, NULL), 1);
  CHECK_INT(sylva_world_add_plant(w, &young, NULL), 2);
  model m = model_of_snapshot(w);
  model_compare_leaves(&m, w, 4);
  delta_totals t = {0};
  step_and_apply(&m, w, 5, 10, &t);
  CHECK(t.leafless > 0);
  free(m.nodes);
  sylva_world_destroy(w);
}

/* A world in years: a lime of a species with years planted at 5, an IGM oak, and a
 * zone over them from 1 m up. */
static sylva_world *years_world(void) {
  sylva_species_def sp;
  sylva_world *w = oak_world(&sp);
  if (!w) return NULL;
  int oak = 0;
  sp.years = 1;
  int lime = sylva_world_add_species(w, &sp, "lime");
  sylva_obstacle_def zone = {"crowns", {-5, -5, 1}, {5, 5, 5}, SYLVA_OBSTACLE_ZONE, {0}};
  CHECK(sylva_world_add_obstacle(w, &zone) >= 0);
  const double a[][3] = {{-1, 0, 0}}, b[][3] = {{1, 0, 0}};
  sylva_plant_def pa = {lime, "lime", a, 1, 5, NULL, 0}, pb = {oak, "oak", b, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &pa, NULL), 0);
  CHECK_INT(sylva_world_add_plant(w, &pb, NULL), 1);
  return w;
}

/* The messages of a run in years with a start year: the snapshot names the start
 * year and its stats carry ages (null for the IGM oak), crown diameter and crown
 * height; each delta's stats are the stats line's, zones dated in calendar years. */
static void test_years_messages(void) {
  sylva_world *w = years_world();
  if (!w) return;
  CHECK(sylva_encode_years(w));
  char *snap = sylva_msg_snapshot(4, 10, w, 2027, NULL);
  CHECK(snap && strstr(snap, ",\"sky\":\"zenith\",\"start_year\":2027,\"foliage\":["));
  CHECK(snap && strstr(snap, "{\"plant\":\"lime\",\"stem\":0,\"age\":5,\"height\":"));
  CHECK(snap && strstr(snap, "{\"plant\":\"oak\",\"stem\":0,\"age\":null,\"height\":"));
  CHECK(snap && strstr(snap, ",\"crown_diameter\":") && strstr(snap, ",\"crown_height\":"));
  free(snap);
  int entered = 0;
  for (int it = 1; it <= 12; it++) {
    const sylva_journal *j = NULL;
    CHECK_INT(sylva_world_step(w, &j), 0);
    if (!j) break;
    char *delta = sylva_msg_delta(4, 10 + it, w, j, 2027);
    char *line = sylva_encode_stats_line(w, j, 0, 2027);
    cJSON *dj = VALID_JSON(delta), *lj = line ? cJSON_Parse(line) : NULL;
    CHECK(lj && num_of(lj, "year") == 2027 + it);
    const cJSON *stats = cJSON_GetObjectItemCaseSensitive(dj, "stats");
    CHECK(lj && cJSON_Compare(cJSON_GetObjectItemCaseSensitive(lj, "stems"), stats, true));
    CHECK_INT(num_of(cJSON_GetArrayItem(stats, 0), "age"), 5 + it);
    CHECK(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(stats, 1), "age")));
    sylva_conflicts c = sylva_world_stem_conflicts(w, 0);
    if (c.zone_count) {
      entered++;
      const cJSON *z = cJSON_GetObjectItemCaseSensitive(
          cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(stats, 0), "zones"), "crowns");
      CHECK_INT(num_of(z, "first"), 2027 + c.zones[0].first);
      char *stored = sylva_encode_stem_conflicts(w, 0, false, 2027);
      char want[96];
      snprintf(want, sizeof want, "{\"crowns\":{\"nodes\":%lld,\"first\":%d}}",
               (long long)c.zones[0].nodes, 2027 + (int)c.zones[0].first);
      CHECK_STR(stored, want);
      free(stored);
    }
    cJSON_Delete(dj);
    cJSON_Delete(lj);
    free(delta);
    free(line);
  }
  CHECK(entered > 0);
  sylva_world_destroy(w);
  /* a world without years carries none of it */
  sylva_world *plain = snapshot_world();
  CHECK(plain && !sylva_encode_years(plain));
  sylva_world_destroy(plain);
}

/* The messages of a stand (docs/model.md, "Stands"): six oaks with a background
 * mortality. The snapshot and each delta carry "stand" after canopy_cover, the line's
 * stand object in compact form, and their stats are the line's stems (alive, died and
 * vigour among them); some stems die. A world without stands carries none. */
static void test_stand_messages(void) {
  sylva_species_def sp;
  sylva_world *w = oak_world(&sp);
  if (!w) return;
  sp.mortality = 0.05;
  CHECK_INT(sylva_world_add_species(w, &sp, "frail"), 1);
  for (int k = 0; k < 6; k++) {
    const double root[][3] = {{-2.5 + (k % 3) * 2.5, -1.5 + (k / 3) * 3.0, 0}};
    char label[8];
    snprintf(label, sizeof label, "p%d", k);
    sylva_plant_def p = {1, label, root, 1, 0, NULL, 0};
    CHECK_INT(sylva_world_add_plant(w, &p, NULL), k);
  }
  CHECK(sylva_encode_stand(w));
  char *snap = sylva_msg_snapshot(4, 10, w, 0, "\"s\"");
  cJSON *sj = VALID_JSON(snap);
  const cJSON *stand = cJSON_GetObjectItemCaseSensitive(sj, "stand");
  CHECK(snap && strstr(snap, ",\"stand\":{\"area\":") && strstr(snap, "},\"ref\":\"s\"}"));
  CHECK(snap && strstr(snap, ",\"canopy_cover\":") < strstr(snap, ",\"stand\":"));
  CHECK_INT(num_of(stand, "alive"), 6);
  CHECK_INT(num_of(stand, "died"), 0);
  CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(
      cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(sj, "stats"), 0), "alive")));
  cJSON_Delete(sj);
  free(snap);
  int died = 0;
  for (int it = 1; it <= 10; it++) {
    const sylva_journal *j = NULL;
    CHECK_INT(sylva_world_step(w, &j), 0);
    if (!j) break;
    char *delta = sylva_msg_delta(4, 10 + it, w, j, 0);
    char *line = sylva_encode_stats_line(w, j, 0, 0);
    cJSON *dj = VALID_JSON(delta), *lj = line ? cJSON_Parse(line) : NULL;
    CHECK(delta && strstr(delta, "],\"canopy_cover\":") < strstr(delta, ",\"stand\":{\"area\":") &&
          strcmp(delta + strlen(delta) - 2, "}}") == 0);
    CHECK(lj && cJSON_Compare(cJSON_GetObjectItemCaseSensitive(lj, "stems"),
                              cJSON_GetObjectItemCaseSensitive(dj, "stats"), true));
    CHECK(lj && cJSON_Compare(cJSON_GetObjectItemCaseSensitive(lj, "stand"),
                              cJSON_GetObjectItemCaseSensitive(dj, "stand"), true));
    died += (int)num_of(cJSON_GetObjectItemCaseSensitive(dj, "stand"), "died");
    cJSON_Delete(dj);
    cJSON_Delete(lj);
    free(delta);
    free(line);
  }
  printf("stand: %d of 6 stems died in 10 iterations\n", died);
  CHECK(died > 0);
  /* a later snapshot: the stand as the world gives it, the dead stems' died */
  snap = sylva_msg_snapshot(4, 30, w, 2030, NULL);
  sj = VALID_JSON(snap);
  stand = cJSON_GetObjectItemCaseSensitive(sj, "stand");
  sylva_stand_stats st;
  sylva_world_stand(w, &st);
  CHECK_INT(num_of(stand, "alive"), st.alive);
  CHECK_INT(num_of(stand, "alive"), 6 - died);
  const cJSON *e;
  int dead = 0;
  cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(sj, "stats")) {
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(e, "died");
    if (!cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(e, "alive"))) {
      dead++;
      CHECK(cJSON_IsNumber(d) && d->valueint > 2030 && d->valueint <= 2040);
    } else {
      CHECK(cJSON_IsNull(d));
    }
  }
  CHECK_INT(dead, died);
  cJSON_Delete(sj);
  free(snap);
  sylva_world_destroy(w);
  /* a world without stands carries none of it */
  sylva_world *plain = snapshot_world();
  CHECK(plain && !sylva_encode_stand(plain));
  snap = plain ? sylva_msg_snapshot(4, 10, plain, 0, NULL) : NULL;
  CHECK(snap && !strstr(snap, "\"stand\"") && !strstr(snap, "\"alive\""));
  free(snap);
  sylva_world_destroy(plain);
}

/* A snapshot after 15 iterations holds the skeleton too. */
static void test_later_snapshot(void) {
  sylva_world *w = snapshot_world();
  if (!w) return;
  grow(w, 15);
  char *snap = sylva_msg_snapshot(4, 25, w, 0, NULL);
  cJSON *sj = VALID_JSON(snap);
  check_snapshot_matches_skeleton(snap, w);
  if (sj) {
    CHECK_INT(num_of(sj, "iteration"), 15);
    CHECK(cJSON_GetObjectItemCaseSensitive(sj, "ref") == NULL);
    model fresh = {0};
    model_load_snapshot(&fresh, sj);
    compare_with_skeleton(&fresh, w, 15);
    CHECK(model_compare_leaves(&fresh, w, 15) > 0);
    free(fresh.nodes);
  }
  cJSON_Delete(sj);
  free(snap);
  sylva_world_destroy(w);
}

/* ---- light slice ---- */

static int b64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

/* Decodes padded base64; NULL if malformed. */
static unsigned char *b64_decode(const char *s, size_t *n) {
  size_t len = strlen(s);
  if (len % 4) return NULL;
  unsigned char *out = malloc(len / 4 * 3 + 1);
  if (!out) return NULL;
  size_t k = 0;
  for (size_t i = 0; i < len; i += 4) {
    int v[4];
    int pad = 0;
    for (int q = 0; q < 4; q++) {
      if (s[i + q] == '=' && i + 4 == len && q >= 2) {
        v[q] = 0;
        pad++;
      } else if ((v[q] = b64_value(s[i + q])) < 0 || pad) {
        free(out);
        return NULL;
      }
    }
    uint32_t x = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)v[2] << 6 | (uint32_t)v[3];
    out[k++] = (unsigned char)(x >> 16);
    if (pad < 2) out[k++] = (unsigned char)(x >> 8);
    if (pad < 1) out[k++] = (unsigned char)x;
  }
  *n = k;
  return out;
}

static void check_slice(const sylva_world *w, double z, double want_z, const char *ref,
                        unsigned char **values_out, int *nx_out) {
  char *text = sylva_msg_light_slice(2, w, z, ref);
  cJSON *j = VALID_JSON(text);
  *values_out = NULL;
  if (j) {
    const sylva_world_def *def = sylva_world_get_def(w);
    int dims[3];
    sylva_world_dims(w, dims);
    CHECK_STR(str_of(j, "type"), "light_slice");
    CHECK_INT(num_of(j, "run"), 2);
    CHECK_INT(num_of(j, "iteration"), sylva_world_iteration(w));
    CHECK_NEAR(num_of(j, "z"), want_z, 1e-9);
    CHECK(num_of(j, "voxel") == def->voxel);
    const cJSON *origin = cJSON_GetObjectItemCaseSensitive(j, "origin");
    CHECK(item_num(origin, 0) == def->min[0] && item_num(origin, 1) == def->min[1]);
    CHECK_INT(num_of(j, "nx"), dims[0]);
    CHECK_INT(num_of(j, "ny"), dims[1]);
    if (ref) CHECK_STR(str_of(j, "ref"), "s");
    size_t n = 0;
    const char *b64 = str_of(j, "values");
    unsigned char *values = b64 ? b64_decode(b64, &n) : NULL;
    CHECK(values != NULL);
    CHECK_INT(n, (size_t)dims[0] * (size_t)dims[1]);
    if (values && n == (size_t)dims[0] * (size_t)dims[1]) {
      /* every byte is round(light * 255) at the voxel centre, x fastest */
      size_t differ = 0;
      for (int y = 0; y < dims[1]; y++)
        for (int x = 0; x < dims[0]; x++) {
          double p[3] = {def->min[0] + (x + 0.5) * def->voxel, def->min[1] + (y + 0.5) * def->voxel,
                         want_z};
          long want = lround(sylva_world_light_at(w, p) * 255);
          long got = values[(size_t)y * (size_t)dims[0] + (size_t)x];
          if (want != got || want < 0 || want > 255) differ++;
        }
      CHECK_INT(differ, 0);
      *values_out = values;
      *nx_out = dims[0];
    } else {
      free(values);
    }
  }
  cJSON_Delete(j);
  free(text);
}

/* The world of the light-slice tests, grown 3 iterations: a tree beside a board over
 * x in [0, 2), y in [-1.5, 1.5), z in [2, 2.2). */
static sylva_world *board_world(void) {
  sylva_world_def def = sylva_default_world_def();
  def.min[0] = -2, def.min[1] = -1.5, def.max[0] = 2, def.max[1] = 1.5, def.max[2] = 4;
  def.voxel = 0.1;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  if (!w) return NULL;
  sylva_obstacle_def board = {.label = "board", .min = {0, -1.5, 2}, .max = {2, 1.5, 2.2}};
  CHECK(sylva_world_add_obstacle(w, &board) >= 0);
  sylva_species_def sp = sylva_default_species_def();
  sp.tropism[2] = 1;
  int species = sylva_world_add_species(w, &sp, "oak");
  const double roots[][3] = {{-1, 0, 0}};
  sylva_plant_def tree = {species, "t1", roots, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &tree, NULL), 0);
  grow(w, 3);
  return w;
}

/* The cells of a slice over the board, x in [20, 40) and y in [0, 30), that are 0. */
static size_t dark_over_board(const unsigned char *values, int nx) {
  size_t dark = 0;
  for (int y = 0; y < 30; y++)
    for (int x = 20; x < 40; x++) dark += values[y * nx + x] == 0;
  return dark;
}

/* Inside the board and just under it, dark over the board and light beside it. */
static void test_light_slice_board(void) {
  sylva_world *w = board_world();
  if (!w) return;
  static const struct {
    double z, want_z;
    const char *ref;
  } slices[] = {{2.1, 2.15, "\"s\""}, {1.95, 1.95, NULL}};
  for (size_t i = 0; i < sizeof slices / sizeof slices[0]; i++) {
    unsigned char *values = NULL;
    int nx = 0;
    check_slice(w, slices[i].z, slices[i].want_z, slices[i].ref, &values, &nx);
    if (values) {
      CHECK_INT(dark_over_board(values, nx), 20 * 30);
      CHECK(values[15 * nx + 2] > 0);
    }
    free(values);
  }
  sylva_world_destroy(w);
}

/* The top layer is in full light (z clamped into the world). */
static void test_light_slice_top(void) {
  sylva_world *w = board_world();
  if (!w) return;
  unsigned char *values = NULL;
  int nx = 0;
  check_slice(w, 1e9, 3.95, NULL, &values, &nx);
  if (values) {
    size_t full = 0;
    for (int i = 0; i < 40 * 30; i++) full += values[i] == 255;
    CHECK_INT(full, 40 * 30);
  }
  free(values);
  sylva_world_destroy(w);
}

/* z is clamped into the world and taken to its layer as the core's voxel lookup does. */
static void test_light_slice_layers(void) {
  sylva_world *w = board_world();
  if (!w) return;
  unsigned char *values = NULL;
  int nx = 0;
  /* z asked, z of the layer's centre: 0.3 / 0.1 is 2.9999999999999996, layer 2 */
  static const double z[][2] = {{-7, 0.05}, {NAN, 0.05}, {4.0, 3.95}, {0.3, 0.25}};
  for (size_t i = 0; i < sizeof z / sizeof z[0]; i++) {
    check_slice(w, z[i][0], z[i][1], NULL, &values, &nx);
    free(values);
  }
  sylva_world_destroy(w);
}

/* An odd number of cells exercises base64 padding: 1 x 1, 2 x 1, 3 x 1 and 4 x 1. */
static void test_light_slice_padding(void) {
  for (int cells = 1; cells <= 4; cells++) {
    sylva_world_def d = sylva_default_world_def();
    d.min[0] = 0, d.max[0] = cells * 0.5, d.min[1] = 0, d.max[1] = 0.5, d.max[2] = 1;
    d.voxel = 0.5;
    sylva_world *w = NULL;
    CHECK_INT(sylva_world_create(&d, &w), 0);
    if (!w) continue;
    unsigned char *values = NULL;
    int nx = 0;
    check_slice(w, 0.2, 0.25, NULL, &values, &nx);
    CHECK(values != NULL);
    free(values);
    sylva_world_destroy(w);
  }
}

int main(int argc, char **argv) {
  if (argc >= 2 && strcmp(argv[1], "--jsontestsuite") == 0 && (argc == 3 || argc == 4)) {
    DIR *d = opendir(argv[2]);
    if (!d) {
      printf("skip: no JSONTestSuite at %s (meson option jsontestsuite)\n", argv[2]);
      return 77;
    }
    closedir(d);
    suite_dir = argv[2];
    static const check_test suite[] = {CHECK_TEST(suite_raw), CHECK_TEST(suite_wrapped)};
    CHECK_RUN(argc, argv, 3, suite);
    return check_summary("protocol JSONTestSuite");
  }
  if (argc > 2 || (argc == 2 && argv[1][0] == '-')) {
    fprintf(stderr, "usage: test-protocol [TEST] | test-protocol --jsontestsuite DIR [TEST]\n");
    return 2;
  }
  static const check_test tests[] = {
      CHECK_TEST(valid_hello), CHECK_TEST(valid_numeric_ids), CHECK_TEST(valid_create),
      CHECK_TEST(valid_create_empty_site), CHECK_TEST(valid_subscribe), CHECK_TEST(valid_control),
      CHECK_TEST(valid_edit), CHECK_TEST(valid_fork_get_light), CHECK_TEST(valid_names),
      CHECK_TEST(invalid_type_and_id), CHECK_TEST(invalid_keys), CHECK_TEST(invalid_syntax),
      CHECK_TEST(invalid_hello), CHECK_TEST(invalid_create), CHECK_TEST(invalid_create_scenario),
      CHECK_TEST(invalid_run), CHECK_TEST(invalid_subscribe), CHECK_TEST(invalid_control),
      CHECK_TEST(invalid_edit_plants), CHECK_TEST(invalid_edit_obstacles),
      CHECK_TEST(invalid_edit_list_sizes), CHECK_TEST(invalid_fork), CHECK_TEST(invalid_get_light),
      CHECK_TEST(invalid_keeps_ref), CHECK_TEST(invalid_error_buffer), CHECK_TEST(invalid_long_key),
      CHECK_TEST(depth), CHECK_TEST(encode_welcome), CHECK_TEST(encode_error),
      CHECK_TEST(encode_parse_error), CHECK_TEST(encode_created), CHECK_TEST(encode_status),
      CHECK_TEST(encode_runs), CHECK_TEST(encode_sweep_runs),
      CHECK_TEST(encode_scenarios), CHECK_TEST(snapshot),
      CHECK_TEST(deltas), CHECK_TEST(leaves_after_edit), CHECK_TEST(later_snapshot), CHECK_TEST(years_messages),
      CHECK_TEST(stand_messages),
      CHECK_TEST(light_slice_board),
      CHECK_TEST(light_slice_top), CHECK_TEST(light_slice_layers), CHECK_TEST(light_slice_padding)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("protocol");
}
