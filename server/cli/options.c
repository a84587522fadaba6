#include "options.h"

#include <errno.h>
#include <limits.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sylva/world.h"

void cli_parser_init(cli_parser *p, const char *command, const cli_option *options, int count,
                     int argc, char **argv) {
  memset(p, 0, sizeof *p);
  p->command = command;
  p->options = options;
  if (count > CLI_MAX_OPTIONS) { /* a programming error: raise CLI_MAX_OPTIONS */
    fprintf(stderr, "sylva %s: %d options, more than CLI_MAX_OPTIONS\n", command, count);
    abort();
  }
  p->count = count;
  p->argc = argc;
  p->argv = argv;
  /* A leading ':' makes getopt report a missing argument as ':' and stay silent. */
  size_t n = 0;
  p->short_options[n++] = ':';
  for (int i = 0; i < p->count; i++) {
    p->long_options[i] = (struct option){options[i].name,
                                         options[i].arg ? required_argument : no_argument, NULL,
                                         256 + i};
    if (options[i].short_name) {
      p->short_options[n++] = options[i].short_name;
      if (options[i].arg) p->short_options[n++] = ':';
    }
  }
  p->short_options[n] = '\0';
  opterr = 0;
  optind = 1;
}

static int option_index(const cli_parser *p, int value) {
  if (value >= 256 && value < 256 + p->count) return value - 256;
  for (int i = 0; i < p->count; i++)
    if (value && p->options[i].short_name == value) return i;
  return -1;
}

int cli_next(cli_parser *p, const char **arg, int *first_positional) {
  *arg = NULL;
  int c = getopt_long(p->argc, p->argv, p->short_options, p->long_options, NULL);
  if (c == -1) {
    *first_positional = optind;
    return -1;
  }
  const char *seen = optind > 0 && optind <= p->argc ? p->argv[optind - 1] : "?";
  if (c == ':' || c == '?') {
    int i = option_index(p, optopt);
    if (c == ':' && i >= 0)
      cli_usage_error(p->command, "option --%s needs an argument (%s): %s", p->options[i].name,
                      p->options[i].arg, p->options[i].help);
    else if (c == ':')
      cli_usage_error(p->command, "option '%s' needs an argument", seen);
    else if (i >= 0 && !p->options[i].arg)
      cli_usage_error(p->command, "option --%s takes no argument", p->options[i].name);
    else if (optopt > 0 && optopt < 256)
      cli_usage_error(p->command, "unknown option '-%c'", optopt);
    else
      cli_usage_error(p->command, "unknown option '%s'", seen);
    return -2;
  }
  int i = option_index(p, c);
  if (i < 0) {
    cli_usage_error(p->command, "unknown option '%s'", seen);
    return -2;
  }
  *arg = p->options[i].arg ? optarg : NULL;
  return i;
}

void cli_print_options(FILE *f, const cli_option *options, int count) {
  for (int i = 0; i < count; i++) {
    char left[64];
    snprintf(left, sizeof left, "%s%c%s--%s%s%s", options[i].short_name ? "-" : " ",
             options[i].short_name ? options[i].short_name : ' ',
             options[i].short_name ? ", " : "  ", options[i].name, options[i].arg ? " " : "",
             options[i].arg ? options[i].arg : "");
    fprintf(f, "  %-22s %s\n", left, options[i].help);
  }
}

int cli_usage_error(const char *command, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "sylva %s: ", command);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
  fprintf(stderr, "\nTry 'sylva %s --help'.\n", command);
  return CLI_EXIT_USAGE;
}

int cli_parse_u64(const char *command, const char *option, const char *text, uint64_t lo,
                  uint64_t hi, uint64_t *out) {
  bool digits = text[0] != '\0';
  for (const char *c = text; *c; c++)
    if (*c < '0' || *c > '9') digits = false;
  errno = 0;
  char *end = NULL;
  unsigned long long v = digits ? strtoull(text, &end, 10) : 0;
  if (!digits || errno == ERANGE || *end != '\0' || v < lo || v > hi)
    return cli_usage_error(command, "--%s: expected an integer from %llu to %llu, got '%s'",
                           option, (unsigned long long)lo, (unsigned long long)hi, text);
  *out = (uint64_t)v;
  return 0;
}

int cli_parse_threads(const char *command, const char *text, int *out) {
  uint64_t v = 0;
  if (cli_parse_u64(command, "threads", text, 1, SYLVA_MAX_THREADS, &v)) return CLI_EXIT_USAGE;
  *out = (int)v;
  return 0;
}

int cli_cores(void) {
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  return cores < 1 ? 1 : cores > INT_MAX ? INT_MAX : (int)cores;
}

int cli_default_threads(int sharers) {
  int n = cli_cores() / (sharers > 1 ? sharers : 1);
  return n < 1 ? 1 : n > SYLVA_MAX_THREADS ? SYLVA_MAX_THREADS : n;
}
