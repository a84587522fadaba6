/* Small assert macros for the test suites: each failure prints both values and
 * the place; a suite ends with "N passed, N failed" and exits non-zero on failure.
 * A suite is a table of named tests, `static void test_NAME(void)` listed as
 * CHECK_TEST(NAME), that main runs with CHECK_RUN; a name on the command line runs
 * that test alone. */
#ifndef SYLVA_TEST_CHECK_H
#define SYLVA_TEST_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int check_passed, check_failed;

#define CHECK(cond)                                                          \
  do {                                                                       \
    if (cond) check_passed++;                                                \
    else {                                                                   \
      check_failed++;                                                        \
      fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
    }                                                                        \
  } while (0)

#define CHECK_INT(a, b)                                                                     \
  do {                                                                                      \
    long long check_a_ = (long long)(a), check_b_ = (long long)(b);                         \
    if (check_a_ == check_b_) check_passed++;                                               \
    else {                                                                                  \
      check_failed++;                                                                       \
      fprintf(stderr, "%s:%d: %s == %s failed: %lld != %lld\n", __FILE__, __LINE__, #a, #b, \
              check_a_, check_b_);                                                          \
    }                                                                                       \
  } while (0)

#define CHECK_NEAR(a, b, tol)                                                                \
  do {                                                                                       \
    double check_a_ = (double)(a), check_b_ = (double)(b);                                   \
    if (fabs(check_a_ - check_b_) <= (tol)) check_passed++;                                  \
    else {                                                                                   \
      check_failed++;                                                                        \
      fprintf(stderr, "%s:%d: %s ~= %s failed: %.12g != %.12g (tol %g)\n", __FILE__, __LINE__, \
              #a, #b, check_a_, check_b_, (double)(tol));                                    \
    }                                                                                        \
  } while (0)

/* A named test: CHECK_TEST(NAME) is {"NAME", test_NAME}. */
typedef struct check_test {
  const char *name;
  void (*run)(void);
} check_test;
#define CHECK_TEST(name) {#name, test_##name}

/* Runs the test named by argv[i] when there is one (an unknown name runs none),
 * else every test in order. */
static inline void check_run_tests(int argc, char **argv, int i, const check_test *tests,
                                   size_t count) {
  for (size_t k = 0; k < count; k++)
    if (i >= argc || strcmp(argv[i], tests[k].name) == 0) tests[k].run();
}
#define CHECK_RUN(argc, argv, i, tests) \
  check_run_tests((argc), (argv), (i), (tests), sizeof(tests) / sizeof((tests)[0]))

/* Ends a suite: prints the summary line and gives the exit status. A suite in
 * which no check ran fails too (an unknown test name selects nothing). */
static inline int check_summary(const char *suite) {
  printf("%s: %d passed, %d failed\n", suite, check_passed, check_failed);
  if (check_passed + check_failed == 0) {
    fprintf(stderr, "%s: no check ran\n", suite);
    return 1;
  }
  return check_failed ? 1 : 0;
}
#endif
