/* JSON Patch (server/sweep/json_patch.c) against the examples of RFC 6902,
 * Appendix A, and the errors a sweep's variant names. */
#include <cjson/cJSON.h>
#include <stdbool.h>

#include "../check.h"
#include "json_patch.h"

typedef struct patch_case {
  const char *name, *doc, *patch;
  const char *result; /* NULL: the patch must fail, with `error` in its message */
  const char *error;
} patch_case;

static const patch_case cases[] = {
    {"A.1 add an object member", "{\"foo\":\"bar\"}",
     "[{\"op\":\"add\",\"path\":\"/baz\",\"value\":\"qux\"}]", "{\"foo\":\"bar\",\"baz\":\"qux\"}",
     NULL},
    {"A.2 add an array element", "{\"foo\":[\"bar\",\"baz\"]}",
     "[{\"op\":\"add\",\"path\":\"/foo/1\",\"value\":\"qux\"}]",
     "{\"foo\":[\"bar\",\"qux\",\"baz\"]}", NULL},
    {"A.3 remove an object member", "{\"baz\":\"qux\",\"foo\":\"bar\"}",
     "[{\"op\":\"remove\",\"path\":\"/baz\"}]", "{\"foo\":\"bar\"}", NULL},
    {"A.4 remove an array element", "{\"foo\":[\"bar\",\"qux\",\"baz\"]}",
     "[{\"op\":\"remove\",\"path\":\"/foo/1\"}]", "{\"foo\":[\"bar\",\"baz\"]}", NULL},
    {"A.5 replace a value", "{\"baz\":\"qux\",\"foo\":\"bar\"}",
     "[{\"op\":\"replace\",\"path\":\"/baz\",\"value\":\"boo\"}]",
     "{\"baz\":\"boo\",\"foo\":\"bar\"}", NULL},
    {"A.6 move a value", "{\"foo\":{\"bar\":\"baz\",\"waldo\":\"fred\"},\"qux\":{\"corge\":\"grault\"}}",
     "[{\"op\":\"move\",\"from\":\"/foo/waldo\",\"path\":\"/qux/thud\"}]",
     "{\"foo\":{\"bar\":\"baz\"},\"qux\":{\"corge\":\"grault\",\"thud\":\"fred\"}}", NULL},
    {"A.7 move an array element", "{\"foo\":[\"all\",\"grass\",\"cows\",\"eat\"]}",
     "[{\"op\":\"move\",\"from\":\"/foo/1\",\"path\":\"/foo/3\"}]",
     "{\"foo\":[\"all\",\"cows\",\"eat\",\"grass\"]}", NULL},
    {"A.8 test: success", "{\"baz\":\"qux\",\"foo\":[\"a\",2,\"c\"]}",
     "[{\"op\":\"test\",\"path\":\"/baz\",\"value\":\"qux\"},"
     "{\"op\":\"test\",\"path\":\"/foo/1\",\"value\":2}]",
     "{\"baz\":\"qux\",\"foo\":[\"a\",2,\"c\"]}", NULL},
    {"A.9 test: failure", "{\"baz\":\"qux\"}",
     "[{\"op\":\"test\",\"path\":\"/baz\",\"value\":\"bar\"}]", NULL, "0: test /baz"},
    {"A.10 add a nested member", "{\"foo\":\"bar\"}",
     "[{\"op\":\"add\",\"path\":\"/child\",\"value\":{\"grandchild\":{}}}]",
     "{\"foo\":\"bar\",\"child\":{\"grandchild\":{}}}", NULL},
    {"A.11 ignore unknown members", "{\"foo\":\"bar\"}",
     "[{\"op\":\"add\",\"path\":\"/baz\",\"value\":\"qux\",\"xyz\":123}]",
     "{\"foo\":\"bar\",\"baz\":\"qux\"}", NULL},
    {"A.12 add to a missing target", "{\"foo\":\"bar\"}",
     "[{\"op\":\"add\",\"path\":\"/baz/bat\",\"value\":\"qux\"}]", NULL, "/baz does not exist"},
    {"A.14 ~ escapes", "{\"/\":9,\"~1\":10}",
     "[{\"op\":\"test\",\"path\":\"/~01\",\"value\":10}]", "{\"/\":9,\"~1\":10}", NULL},
    {"A.15 test a string against a number", "{\"/\":9,\"~1\":10}",
     "[{\"op\":\"test\",\"path\":\"/~01\",\"value\":\"10\"}]", NULL, "not the value"},
    {"A.16 add an array value", "{\"foo\":[\"bar\"]}",
     "[{\"op\":\"add\",\"path\":\"/foo/-\",\"value\":[\"abc\",\"def\"]}]",
     "{\"foo\":[\"bar\",[\"abc\",\"def\"]]}", NULL},
    {"copy", "{\"a\":{\"b\":1}}", "[{\"op\":\"copy\",\"from\":\"/a\",\"path\":\"/c\"}]",
     "{\"a\":{\"b\":1},\"c\":{\"b\":1}}", NULL},
    {"replace the whole document", "{\"a\":1}", "[{\"op\":\"replace\",\"path\":\"\",\"value\":[1]}]",
     "[1]", NULL},
    {"remove past an array's end", "{\"obstacles\":[1,2,3]}",
     "[{\"op\":\"remove\",\"path\":\"/obstacles/7\"}]", NULL,
     "0: remove /obstacles/7: /obstacles/7 does not exist (the array has 3 elements)"},
    {"a leading zero is no index", "{\"a\":[1,2]}", "[{\"op\":\"remove\",\"path\":\"/a/01\"}]",
     NULL, "does not exist"},
    {"the second operation fails: nothing changes", "{\"a\":1}",
     "[{\"op\":\"add\",\"path\":\"/b\",\"value\":2},{\"op\":\"remove\",\"path\":\"/c\"}]", NULL,
     "1: remove /c"},
    {"an unknown op", "{}", "[{\"op\":\"merge\",\"path\":\"/a\"}]", NULL, "unknown op \"merge\""},
    {"no value", "{}", "[{\"op\":\"add\",\"path\":\"/a\"}]", NULL, "no \"value\""},
    {"not a pointer", "{}", "[{\"op\":\"add\",\"path\":\"a\",\"value\":1}]", NULL,
     "is not a JSON pointer"},
    {"a bad escape", "{}", "[{\"op\":\"add\",\"path\":\"/a~2\",\"value\":1}]", NULL, "~ escape"},
    {"move into itself", "{\"a\":{\"b\":1}}",
     "[{\"op\":\"move\",\"from\":\"/a\",\"path\":\"/a/c\"}]", NULL, "into itself"},
    {"a patch is an array", "{}", "{\"op\":\"add\"}", NULL, "an array of operations"},
};

static void test_rfc6902(void) {
  for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
    const patch_case *c = &cases[i];
    cJSON *doc = cJSON_Parse(c->doc), *patch = cJSON_Parse(c->patch);
    char *before = cJSON_PrintUnformatted(doc);
    char err[1024] = "";
    int rc = json_patch_apply(&doc, patch, err, sizeof err);
    char *after = cJSON_PrintUnformatted(doc);
    if (c->result) {
      cJSON *want = cJSON_Parse(c->result);
      bool ok = rc == 0 && cJSON_Compare(doc, want, true);
      if (!ok) fprintf(stderr, "%s: got %s (%s)\n", c->name, after, err);
      CHECK(ok);
      cJSON_Delete(want);
    } else {
      bool ok = rc != 0 && strstr(err, c->error) && strcmp(before, after) == 0;
      if (!ok) fprintf(stderr, "%s: rc %d, error \"%s\", document %s\n", c->name, rc, err, after);
      CHECK(ok);
    }
    free(before);
    free(after);
    cJSON_Delete(doc);
    cJSON_Delete(patch);
  }
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(rfc6902)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("json_patch");
}
