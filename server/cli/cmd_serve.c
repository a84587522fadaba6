/* `sylva serve`: the daemon. */
#include <arpa/inet.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "commands.h"
#include "daemon.h"
#include "options.h"

enum { OPT_DB, OPT_LISTEN, OPT_RUN, OPT_WEB, OPT_SCENARIOS, OPT_TOKEN, OPT_TOKEN_FILE,
       OPT_PUBLIC_READ, OPT_HOST, OPT_ORIGIN, OPT_INSECURE, OPT_MAX_MESSAGE, OPT_RATE,
       OPT_THREADS, OPT_WORKERS, OPT_MAX_RUNS, OPT_MAX_STEMS, OPT_MAX_OBSTACLES, OPT_MAX_CLIENTS,
       OPT_MAX_JOBS, OPT_MAX_INPUT, OPT_MAX_BACKLOG, OPT_MEMORY, OPT_WORK_NICE, OPT_TRACE, OPT_HELP, OPT_COUNT };

static const cli_option serve_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (default sylva.db)"},
    [OPT_LISTEN] = {"listen", 0, "HOST:PORT", "where to listen (default 127.0.0.1:8080)"},
    [OPT_RUN] = {"run", 0, "SCENARIO.json",
                 "start growing this scenario (unless a run of its name exists)"},
    [OPT_WEB] = {"web", 0, "DIR", "the viewer's files (default ./web when it exists)"},
    [OPT_SCENARIOS] = {"scenarios", 0, "DIR",
                       "ready scenarios offered to clients (default ./scenarios when it exists)"},
    [OPT_TOKEN] = {"token", 0, "T",
                   "every message and route but /healthz and the viewer's files need this "
                   "token (shows in ps: prefer --token-file or SYLVA_TOKEN)"},
    [OPT_TOKEN_FILE] = {"token-file", 0, "FILE", "the token: the first line of FILE"},
    [OPT_PUBLIC_READ] = {"public-read", 0, NULL,
                         "with a token, only changing messages need it; reading is open"},
    [OPT_HOST] = {"allow-host", 0, "NAME",
                  "also serve requests whose Host is NAME (repeatable; the listen address, "
                  "localhost, 127.0.0.1 and [::1] always are)"},
    [OPT_ORIGIN] = {"allow-origin", 0, "ORIGIN",
                    "also accept WebSockets from this Origin (repeatable)"},
    [OPT_INSECURE] = {"insecure", 0, NULL, "allow a non-loopback address without --token"},
    [OPT_MAX_MESSAGE] = {"max-message", 0, "BYTES", "largest client message (default 1 MiB)"},
    [OPT_RATE] = {"rate-limit", 0, "N", "most client messages per second (default 50)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "threads each run's world grows on (1 to 256, default: the cores)"},
    [OPT_WORKERS] = {"workers", 0, "N", "threads that grow the runs, in turn (default 2)"},
    [OPT_MAX_RUNS] = {"max-runs", 0, "N", "most runs held, forks included (default 64)"},
    [OPT_MAX_STEMS] = {"max-stems", 0, "N", "most stems in one world (default 2000)"},
    [OPT_MAX_OBSTACLES] = {"max-obstacles", 0, "N", "most obstacles in one world (default 10000)"},
    [OPT_MAX_CLIENTS] = {"max-clients", 0, "N",
                         "most WebSocket clients at once (default 1000, and below the limit "
                         "of open files)"},
    [OPT_MAX_JOBS] = {"max-jobs", 0, "N",
                      "most exports, history snapshots and forks at once (default 2)"},
    [OPT_MAX_INPUT] = {"max-input", 0, "BYTES",
                       "most bytes of unfinished messages of all clients (default 64 MiB)"},
    [OPT_MAX_BACKLOG] = {"max-backlog", 0, "BYTES",
                         "most bytes waiting for one client behind the message going out to "
                         "it (default 64 MiB); past it the client is closed as too slow"},
    [OPT_MEMORY] = {"memory-budget", 0, "MIB",
                    "memory the runs' worlds may take, by estimate (default 4096)"},
    [OPT_WORK_NICE] = {"work-nice", 0, "N",
                       "run the growth and the exports N steps of niceness below the loop that "
                       "serves the clients (0 to 19, default 10)"},
    [OPT_TRACE] = {"trace-iterations", 0, "FILE",
                   "append a line per grown iteration: run, iteration, and the monotonic "
                   "seconds when its step returned, was stored, its delta encoded and handed "
                   "out"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

/* The integer limits OPT_WORKERS to OPT_MAX_JOBS: the highest value and where it
 * goes in server_options (the lowest is 1). */
typedef struct cli_int_option {
  uint64_t hi;
  size_t offset;
} cli_int_option;

static const cli_int_option int_options[] = {
    {64, offsetof(server_options, workers)},
    {100000, offsetof(server_options, max_runs)},
    {1000000, offsetof(server_options, max_stems)},
    {1000000, offsetof(server_options, max_obstacles)},
    {1000000, offsetof(server_options, clients.max_clients)},
    {64, offsetof(server_options, max_jobs)},
};
_Static_assert(sizeof int_options / sizeof int_options[0] == OPT_MAX_JOBS - OPT_WORKERS + 1,
               "one entry per integer limit");

static void serve_usage(FILE *f) {
  fputs("Usage: sylva serve [OPTIONS]\n"
        "\n"
        "Runs the daemon: one port serves the viewer's files, the WebSocket endpoint /ws\n"
        "(subprotocol sylva.v1), /healthz, /metrics (Prometheus), /api/runs,\n"
        "/api/runs/NAME/stats.csv, /api/runs/NAME/export?format=F[&iteration=T]\n"
        "[&obstacles=1] (what 'sylva export' writes: F is skeleton, obj, ply, csv or\n"
        "glb; T the run's current iteration unless given), /api/sweeps/NAME/report.EXT\n"
        "[?years=10,20,40] (what 'sylva report' writes: EXT is html, csv or pdf) and\n"
        "/api/scenarios/NAME (the file NAME.json of --scenarios). Stored runs are loaded\n"
        "at start; those that were running continue from their last stored iteration.\n"
        "SIGINT or SIGTERM stops it: iterations in flight are stored and clients are\n"
        "closed with 1001.\n"
        "\n"
        "The token may also come from the environment variable SYLVA_TOKEN.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, serve_options, OPT_COUNT);
}

static bool is_dir(const char *path) {
  struct stat sb;
  return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

/* The token of --token-file: its first line, without the line end. */
static int read_token_file(const char *path, char *out, size_t size) {
  FILE *f = fopen(path, "r");
  if (!f) return cli_usage_error("serve", "--token-file: cannot read '%s'", path);
  bool got = fgets(out, (int)size, f) != NULL;
  fclose(f);
  if (got) out[strcspn(out, "\r\n")] = 0;
  if (!got || !out[0])
    return cli_usage_error("serve", "--token-file: '%s' has no token on its first line", path);
  return CLI_EXIT_OK;
}

static bool loopback(const char *host) {
  struct in_addr a4;
  if (strcmp(host, "localhost") == 0) return true;
  if (inet_pton(AF_INET, host, &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  return strcmp(host, "::1") == 0;
}

int cmd_serve(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "serve", serve_options, OPT_COUNT, argc, argv);
  server_options o = {
      .db = "sylva.db", .host = "127.0.0.1", .port = 8080,
      .clients = {.max_message = DAEMON_MAX_MESSAGE, .rate_limit = DAEMON_RATE_LIMIT,
                  .max_pending = DAEMON_MAX_PENDING, .max_clients = DAEMON_MAX_CLIENTS,
                  .max_input = DAEMON_MAX_INPUT, .message_ms = DAEMON_MESSAGE_MS},
      .workers = DAEMON_WORKERS, .threads = cli_default_threads(1),
      .work_nice = DAEMON_WORK_NICE,
      .max_runs = DAEMON_MAX_RUNS, .max_stems = DAEMON_MAX_STEMS,
      .max_obstacles = DAEMON_MAX_OBSTACLES, .max_jobs = DAEMON_MAX_JOBS,
      .memory_budget = (size_t)DAEMON_MEMORY_BUDGET_MIB << 20};
  static char host[256], token[512];
  bool insecure = false, web_given = false, scenarios_given = false;
  const char *arg;
  int first = argc, opt;
  uint64_t v;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: o.db = arg; break;
    case OPT_LISTEN: {
      const char *colon = strrchr(arg, ':');
      if (!colon || colon == arg || (size_t)(colon - arg) >= sizeof host)
        return cli_usage_error("serve", "--listen: expected HOST:PORT, got '%s'", arg);
      memcpy(host, arg, (size_t)(colon - arg));
      host[colon - arg] = 0;
      if (cli_parse_u64("serve", "listen", colon + 1, 1, 65535, &v)) return CLI_EXIT_USAGE;
      o.host = host;
      o.port = (int)v;
      break;
    }
    case OPT_RUN: o.start_scenario = arg; break;
    case OPT_WEB:
      if (!is_dir(arg)) return cli_usage_error("serve", "--web: '%s' is not a directory", arg);
      o.web = arg;
      web_given = true;
      break;
    case OPT_SCENARIOS:
      if (!is_dir(arg)) return cli_usage_error("serve", "--scenarios: '%s' is not a directory", arg);
      o.scenarios = arg;
      scenarios_given = true;
      break;
    case OPT_TOKEN:
      if (!arg[0]) return cli_usage_error("serve", "--token: empty token");
      o.token = arg;
      break;
    case OPT_TOKEN_FILE:
      if (read_token_file(arg, token, sizeof token)) return CLI_EXIT_USAGE;
      o.token = token;
      break;
    case OPT_PUBLIC_READ: o.public_read = true; break;
    case OPT_HOST:
      if (o.host_count == ACCESS_MAX_HOSTS)
        return cli_usage_error("serve", "--allow-host: at most %d", ACCESS_MAX_HOSTS);
      if (!arg[0] || strpbrk(arg, ":/ "))
        return cli_usage_error("serve", "--allow-host: expected a host name without a port, got "
                               "'%s'", arg);
      o.hosts[o.host_count++] = arg;
      break;
    case OPT_ORIGIN:
      if (o.origin_count == DAEMON_MAX_ORIGINS)
        return cli_usage_error("serve", "--allow-origin: at most %d", DAEMON_MAX_ORIGINS);
      o.origins[o.origin_count++] = arg;
      break;
    case OPT_INSECURE: insecure = true; break;
    case OPT_MAX_MESSAGE:
      if (cli_parse_u64("serve", "max-message", arg, 1024, 1u << 30, &v)) return CLI_EXIT_USAGE;
      o.clients.max_message = (size_t)v;
      break;
    case OPT_RATE:
      if (cli_parse_u64("serve", "rate-limit", arg, 1, 1000000, &v)) return CLI_EXIT_USAGE;
      o.clients.rate_limit = (int)v;
      break;
    case OPT_THREADS:
      if (cli_parse_threads("serve", arg, &o.threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_WORKERS: case OPT_MAX_RUNS: case OPT_MAX_STEMS: case OPT_MAX_OBSTACLES:
    case OPT_MAX_CLIENTS: case OPT_MAX_JOBS: {
      const cli_int_option *n = &int_options[opt - OPT_WORKERS];
      if (cli_parse_u64("serve", serve_options[opt].name, arg, 1, n->hi, &v))
        return CLI_EXIT_USAGE;
      *(int *)((char *)&o + n->offset) = (int)v;
      break;
    }
    case OPT_MAX_INPUT:
      if (cli_parse_u64("serve", "max-input", arg, 1024, 1ull << 34, &v)) return CLI_EXIT_USAGE;
      o.clients.max_input = (size_t)v;
      break;
    case OPT_MAX_BACKLOG:
      if (cli_parse_u64("serve", "max-backlog", arg, 1024, 1ull << 34, &v)) return CLI_EXIT_USAGE;
      o.clients.max_pending = (size_t)v;
      break;
    case OPT_MEMORY:
      if (cli_parse_u64("serve", "memory-budget", arg, 16, 1u << 20, &v)) return CLI_EXIT_USAGE;
      o.memory_budget = (size_t)v << 20;
      break;
    case OPT_WORK_NICE:
      if (cli_parse_u64("serve", "work-nice", arg, 0, 19, &v)) return CLI_EXIT_USAGE;
      o.work_nice = (int)v;
      break;
    case OPT_TRACE:
      if (o.trace) fclose(o.trace);
      if (!(o.trace = fopen(arg, "a")))
        return cli_usage_error("serve", "--trace-iterations: cannot write '%s'", arg);
      setvbuf(o.trace, NULL, _IOLBF, 0); /* each line as it is made */
      break;
    default:
      serve_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("serve", "unexpected argument '%s'", argv[first]);
  const char *env = getenv("SYLVA_TOKEN");
  if (!o.token && env && env[0]) o.token = env;
  if (o.public_read && !o.token)
    return cli_usage_error("serve", "--public-read: there is no token (give --token-file, "
                           "SYLVA_TOKEN or --token)");
  if (!loopback(o.host) && !o.token && !insecure)
    return cli_usage_error("serve", "--listen %s is not a loopback address: give --token (or "
                           "--insecure to serve anyone who can reach it)", o.host);
  if (!web_given && is_dir("web")) o.web = "web";
  if (!scenarios_given && is_dir("scenarios")) o.scenarios = "scenarios";
  int rc = server_main(&o);
  if (o.trace) fclose(o.trace);
  return rc;
}
