/* sylva server: command-line options shared by the subcommands (getopt_long). */
#ifndef SYLVA_SERVER_OPTIONS_H
#define SYLVA_SERVER_OPTIONS_H

#include <getopt.h>
#include <stdint.h>
#include <stdio.h>

#include "server_error.h"

/** Exit statuses of the binary (cli.md). */
enum { CLI_EXIT_OK = 0, CLI_EXIT_FAILURE = 1, CLI_EXIT_USAGE = 2 };
/** What an argument parser returns when the command should go on (not an exit
 *  status). */
enum { CLI_PARSED = -1 };

/** Most options one subcommand may declare. */
#define CLI_MAX_OPTIONS 32

/** One option of a subcommand. */
typedef struct cli_option {
  const char *name; /**< long name, without "--" */
  char short_name;  /**< 0 when there is none */
  const char *arg;  /**< name of its argument in the help ("N"), NULL for a flag */
  const char *help; /**< one line */
} cli_option;

/** Walks argv of one subcommand (argv[0] is the subcommand's name). */
typedef struct cli_parser {
  const char *command; /**< "run", for messages */
  const cli_option *options;
  int count;
  int argc;
  char **argv;
  struct option long_options[CLI_MAX_OPTIONS + 1];
  char short_options[2 * CLI_MAX_OPTIONS + 2];
} cli_parser;

/** Prepares a parser; options[] must outlive it. */
void cli_parser_init(cli_parser *p, const char *command, const cli_option *options, int count,
                     int argc, char **argv);

/** The next option: its index in options[] (>= 0) and its argument in *arg (NULL
 *  for a flag); -1 when the options are done (positional arguments are then
 *  argv[*first_positional .. argc)); -2 after printing a usage error to stderr. */
int cli_next(cli_parser *p, const char **arg, int *first_positional);

/** Prints the option table of a subcommand's help. */
void cli_print_options(FILE *f, const cli_option *options, int count);

/** Prints "sylva CMD: message" and a hint to run --help; returns CLI_EXIT_USAGE. */
int cli_usage_error(const char *command, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Parses a decimal integer in [lo, hi] that must be the whole of text (no sign,
 *  no spaces). On error prints "sylva CMD: --opt: ..." and returns CLI_EXIT_USAGE. */
int cli_parse_u64(const char *command, const char *option, const char *text, uint64_t lo,
                  uint64_t hi, uint64_t *out);

/** The value of a --threads option: an integer from 1 to SYLVA_MAX_THREADS, parsed
 *  and refused as cli_parse_u64 does ("sylva CMD: --threads: expected an integer
 *  from 1 to 256, got 'abc'"). */
int cli_parse_threads(const char *command, const char *text, int *out);

/** The machine's cores online (sysconf), at least 1. */
int cli_cores(void);

/** The default of --threads: the cores shared by `sharers` processes (1: by none),
 *  from 1 to SYLVA_MAX_THREADS. */
int cli_default_threads(int sharers);

#endif
