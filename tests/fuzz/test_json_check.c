/* sylva_json_check against JSONTestSuite (y_* accepted, n_* rejected, i_* pinned)
 * and against hand-written cases for each leniency of cJSON 1.7.15. */
#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../list_dir.h"
#include "../read_file.h"
#include "sylva/json_check.h"

/* i_* files (implementation-defined) that we accept; every other i_* is rejected
 * (invalid UTF-8, unpaired surrogates, BOM, and i_structure_500_nested_arrays
 * because of the depth limit of 64). */
static const char *const accepted_i[] = {
    "i_number_double_huge_neg_exp.json", "i_number_huge_exp.json",
    "i_number_neg_int_huge_exp.json",    "i_number_pos_double_huge_exp.json",
    "i_number_real_neg_overflow.json",   "i_number_real_pos_overflow.json",
    "i_number_real_underflow.json",      "i_number_too_big_neg_int.json",
    "i_number_too_big_pos_int.json",     "i_number_very_big_negative_int.json",
};

static bool pinned_accept(const char *name) {
  for (size_t i = 0; i < sizeof accepted_i / sizeof accepted_i[0]; i++)
    if (strcmp(name, accepted_i[i]) == 0) return true;
  return false;
}

/* A check that names what failed and how. */
static void record(bool ok, const char *what, const char *detail) {
  if (ok) {
    check_passed++;
  } else {
    check_failed++;
    printf("FAIL %s: %s\n", what, detail);
  }
}

/* ---- hand-written cases: cJSON 1.7.15 accepts every one that must be rejected ---- */

typedef struct text_case {
  const char *text;
  size_t len;
  const char *expect; /* NULL: must be accepted; else a substring of the error */
} text_case;
/* text: a string literal (it may hold NUL bytes) */
#define CASE(text, expect) {text, sizeof text - 1, expect}

/* Checks each case at the depth limit with the flags; test and table name them. */
static void run_table(const char *test, const char *table, const text_case *cases, size_t n,
                      int depth, unsigned flags) {
  for (size_t i = 0; i < n; i++) {
    const text_case *t = &cases[i];
    char err[256], what[128], detail[400];
    int rc = sylva_json_check_ex(t->text, t->len, depth, flags, err, sizeof err);
    snprintf(what, sizeof what, "%s, %s case %zu", test, table, i);
    if (!t->expect) {
      snprintf(detail, sizeof detail, "rejected: %s", err);
      record(rc == 0, what, detail);
    } else {
      snprintf(detail, sizeof detail, "rc %d, error \"%s\", expected \"%s\"", rc, err, t->expect);
      record(rc != 0 && strstr(err, t->expect) != NULL, what, detail);
    }
  }
}
#define RUN_TABLE(cases, depth, flags) \
  run_table(__func__, #cases, cases, sizeof cases / sizeof cases[0], depth, flags)

/* Numbers: no leading zero, digits after the point and in the exponent, no NaN. */
static void test_numbers(void) {
  static const text_case cases[] = {
      CASE("-01", "line 1, column 1 (byte 0): leading zero in number"),
      CASE("[2.]", "column 4 (byte 3): digit expected after the decimal point"),
      CASE("2.e3", "digit expected after the decimal point"),
      CASE("1e", "digit expected in the exponent"),
      CASE("[NaN]", "expected a value, got 'N'"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* Strings: escaped control characters, valid escapes, a closing quote. */
static void test_strings(void) {
  static const text_case cases[] = {
      CASE("\"a\tb\"", "control character U+0009 must be escaped"),
      CASE("\"\\u12G4\"", "four hex digits"),
      CASE("\"\\x41\"", "invalid escape"),
      CASE("\"abc", "unterminated string"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* \u0000 is allowed unless SYLVA_JSON_NO_NUL_ESCAPE. */
static void test_nul_escape(void) {
  static const text_case allowed[] = {CASE("\"a\\u0000b\"", NULL)};
  static const text_case refused[] = {CASE("\"a\\u0000b\"", "\\u0000 (NUL)")};
  RUN_TABLE(allowed, 64, 0);
  RUN_TABLE(refused, 64, SYLVA_JSON_NO_NUL_ESCAPE);
}

/* Form feeds and NUL bytes are no whitespace, before, inside or after the value. */
static void test_stray_bytes(void) {
  static const text_case cases[] = {
      CASE("\f[]", "expected a value, got byte 0x0C"),
      CASE("[]\f", "unexpected byte 0x0C after the JSON value"),
      CASE("[1]\0", "unexpected byte 0x00 after the JSON value"),
      CASE("[\0]", "expected a value, got byte 0x00"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* UTF-8: no overlong form, encoded surrogate, code point above U+10FFFF or cut sequence. */
static void test_utf8(void) {
  static const text_case cases[] = {
      CASE("\"\xC0\xAF\"", "overlong"),
      CASE("\"\xE0\x80\xAF\"", "overlong"),
      CASE("\"\xED\xA0\x80\"", "encoded surrogate U+D800"),
      CASE("\"\xF4\x90\x80\x80\"", "above U+10FFFF"),
      CASE("\"\xF5\x80\x80\x80\"", "invalid UTF-8"),
      CASE("\"\xE2\x82\"", "truncated 3-byte sequence"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* Surrogate escapes come in pairs, high then low. */
static void test_surrogates(void) {
  static const text_case cases[] = {
      CASE("\"\\uD800\"", "unpaired surrogate escape \\uD800"),
      CASE("\"\\uDC00\\uD800\"", "unpaired surrogate escape \\uDC00"),
      CASE("\"\\uD800\\u0041\"", "unpaired surrogate"),
      CASE("\"\\uD834\\uDD1E\"", NULL),
  };
  RUN_TABLE(cases, 64, 0);
}

/* A document is one value in optional whitespace: no BOM, not empty, nothing after it. */
static void test_documents(void) {
  static const text_case cases[] = {
      CASE("\xEF\xBB\xBF{}", "byte order mark"),
      CASE("", "line 1, column 1 (byte 0): empty document"),
      CASE(" \r\n\t ", "empty document"),
      CASE("{}{}", "unexpected '{' after the JSON value"),
      CASE("  {\"a\": [1, -0.5e+3, true, false, null, \"\\u00e9\\n\"]}\r\n", NULL),
  };
  RUN_TABLE(cases, 64, 0);
}

/* Arrays and objects: no trailing comma; string keys, separators, whole literals, an end. */
static void test_structure(void) {
  static const text_case cases[] = {
      CASE("[1,]", "trailing comma before ']'"),
      CASE("{\"a\":1,}", "trailing comma before '}'"),
      CASE("{\"a\" 1}", "expected ':' after the key, got '1'"),
      CASE("{1:1}", "expected a string key, got '1'"),
      CASE("[1 2]", "expected ',' or ']', got '2'"),
      CASE("[tru]", "invalid literal (expected true)"),
      CASE("[", "unexpected end of input, expected a value"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* An error names its line, its column in characters and its byte. */
static void test_positions(void) {
  static const text_case cases[] = {
      CASE("{\n  \"a\": [\n    1,\n    01\n  ]\n}", "line 4, column 5 (byte 22): leading zero"),
      CASE("{\"\xC3\xA9t\xC3\xA9\": -x}", "line 1, column 10 (byte 11): '-' must be followed"),
  };
  RUN_TABLE(cases, 64, 0);
}

/* The depth limit: arrays and objects nested up to it, not deeper. */
static void test_depths(void) {
  static const text_case four[] = {CASE("[[[[]]]]", NULL),
                                   CASE("[[[[[]]]]]", "column 5 (byte 4): nesting deeper than 4")};
  static const text_case two[] = {CASE("{\"a\":{\"b\":{}}}", "nesting deeper than 2")};
  static const text_case none[] = {CASE("0", NULL), CASE("[]", "nesting deeper than 0")};
  RUN_TABLE(four, 4, 0);
  RUN_TABLE(two, 2, 0);
  RUN_TABLE(none, 0, 0);
}

/* A tiny error buffer truncates, a NULL one is allowed. */
static void test_error_buffer(void) {
  char small[8];
  record(sylva_json_check("[01]", 4, 64, small, sizeof small) != 0 && strlen(small) == 7,
         "small buffer", small);
  record(sylva_json_check("[01]", 4, 64, NULL, 0) != 0, "null buffer", "accepted");
}

/* Nesting far beyond the limit neither recurses nor overflows. */
static void test_deep_nesting(void) {
  char small[8];
  size_t n = 200000;
  char *deep = malloc(n);
  if (deep) {
    memset(deep, '[', n);
    record(sylva_json_check(deep, n, 1 << 30, small, sizeof small) != 0, "deep nesting",
           "accepted");
    free(deep);
  }
}

/* sylva_utf8_check on bare text (the daemon's check of a WebSocket text message). */
static void test_utf8_text(void) {
  static const struct {
    const char *text;
    size_t len;
    bool ok;
  } cases[] = {
      {"", 0, true},
      {"plain ascii", 11, true},
      {"\xc3\xa9t\xc3\xa9", 6, true},            /* two-byte */
      {"\xe2\x82\xac", 3, true},                   /* three-byte */
      {"\xf0\x9f\x8c\xb3", 4, true},               /* four-byte */
      {"a\0b", 3, true},                              /* NUL is a character */
      {"\xc0\xaf", 2, false},                        /* overlong */
      {"\xed\xa0\x80", 3, false},                   /* surrogate */
      {"\xf4\x90\x80\x80", 4, false},               /* above U+10FFFF */
      {"\xe2\x82", 2, false},                        /* truncated at the end */
      {"\x80", 1, false},                             /* lone continuation */
      {"\xff", 1, false},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char err[128];
    int rc = sylva_utf8_check(cases[i].text, cases[i].len, err, sizeof err);
    char what[32];
    snprintf(what, sizeof what, "utf8 case %zu", i);
    record((rc == 0) == cases[i].ok, what, cases[i].ok ? err : "accepted");
    if (!cases[i].ok) record(strstr(err, "invalid UTF-8") != NULL, what, err);
  }
}

/* ---- JSONTestSuite ---- */

static const char *suite_dir;

/* Checks every JSONTestSuite file whose name keep() accepts: check(name, rc, err)
 * with sylva_json_check's result at depth 64; returns the number of files. */
static size_t check_files(bool (*keep)(const char *name),
                          void (*check)(const char *name, int rc, const char *err)) {
  size_t count;
  char **names = list_dir(suite_dir, keep, &count);
  if (!names) {
    record(false, suite_dir, "cannot list the JSONTestSuite directory");
    return 0;
  }
  for (size_t i = 0; i < count; i++) {
    char path[4096], err[256] = "";
    snprintf(path, sizeof path, "%s/%s", suite_dir, names[i]);
    size_t len = 0;
    char *text = read_file(path, &len);
    if (!text) {
      record(false, names[i], "cannot read");
      continue;
    }
    int rc = sylva_json_check(text, len, 64, err, sizeof err);
    free(text);
    check(names[i], rc, err);
  }
  list_dir_free(names, count);
  return count;
}

static bool y_file(const char *name) { return name[0] == 'y'; }
static bool n_file(const char *name) { return name[0] == 'n'; }
static bool i_file(const char *name) { return name[0] == 'i'; }

static void accepted(const char *name, int rc, const char *err) {
  char detail[400];
  snprintf(detail, sizeof detail, "rejected: %s", err);
  record(rc == 0, name, detail);
}

static void rejected(const char *name, int rc, const char *err) {
  (void)err;
  record(rc != 0, name, "accepted, must be rejected");
}

static int i_accepted, i_rejected;

static void as_pinned(const char *name, int rc, const char *err) {
  char detail[400];
  if (rc == 0) i_accepted++;
  else i_rejected++;
  snprintf(detail, sizeof detail, "%s, pinned as %s (%s)", rc == 0 ? "accepted" : "rejected",
           pinned_accept(name) ? "accepted" : "rejected", rc ? err : "");
  record((rc == 0) == pinned_accept(name), name, detail);
}

/* Every y_* file is accepted. */
static void test_suite_y(void) {
  printf("JSONTestSuite: %zu y_* files\n", check_files(y_file, accepted));
}

/* Every n_* file is rejected. */
static void test_suite_n(void) {
  printf("JSONTestSuite: %zu n_* files\n", check_files(n_file, rejected));
}

/* Every i_* file is accepted or rejected as pinned in accepted_i. */
static void test_suite_i(void) {
  size_t count = check_files(i_file, as_pinned);
  printf("JSONTestSuite: %zu i_* files (%d accepted, %d rejected)\n", count, i_accepted,
         i_rejected);
}

int main(int argc, char **argv) {
  if (argc != 2 && argc != 3) {
    fprintf(stderr, "usage: %s JSONTestSuite/test_parsing [TEST]\n", argv[0]);
    return 2;
  }
  static const check_test fixed[] = {
      CHECK_TEST(numbers), CHECK_TEST(strings), CHECK_TEST(nul_escape), CHECK_TEST(stray_bytes),
      CHECK_TEST(utf8), CHECK_TEST(surrogates), CHECK_TEST(documents), CHECK_TEST(structure),
      CHECK_TEST(positions), CHECK_TEST(depths), CHECK_TEST(error_buffer),
      CHECK_TEST(deep_nesting), CHECK_TEST(utf8_text)};
  static const check_test suite[] = {CHECK_TEST(suite_y), CHECK_TEST(suite_n), CHECK_TEST(suite_i)};
  CHECK_RUN(argc, argv, 2, fixed);
  DIR *d = opendir(argv[1]);
  if (!d) { /* the fixed cases ran; without a JSONTestSuite copy the rest is skipped */
    printf("skip: no JSONTestSuite at %s (meson option jsontestsuite)\n", argv[1]);
    int rc = check_summary("json-check");
    return rc ? rc : 77;
  }
  closedir(d);
  suite_dir = argv[1];
  CHECK_RUN(argc, argv, 2, suite);
  return check_summary("json-check");
}
