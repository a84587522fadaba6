/* sylva: the status of a run, one list for the store, the protocol and HTTP
 * (docs/protocol.md, docs/cli.md). The names are what the store keeps and what
 * the wire and `sylva runs` show. */
#ifndef SYLVA_RUN_STATUS_H
#define SYLVA_RUN_STATUS_H

/* X(enum name, stored and shown name) */
#define SYLVA_RUN_STATUSES(X)        \
  X(SYLVA_RUN_PAUSED, "paused")      \
  X(SYLVA_RUN_RUNNING, "running")    \
  X(SYLVA_RUN_FINISHED, "finished")  \
  X(SYLVA_RUN_FAILED, "failed")

typedef enum sylva_run_status {
#define SYLVA_RUN_STATUS_ENUM(name, text) name,
  SYLVA_RUN_STATUSES(SYLVA_RUN_STATUS_ENUM)
#undef SYLVA_RUN_STATUS_ENUM
} sylva_run_status;

/** The name of s ("paused", ...); "unknown" for a value not in the list. */
const char *sylva_run_status_name(sylva_run_status s);
/** The status named text: 0 and *out, or -1 when text names none. */
int sylva_run_status_parse(const char *text, sylva_run_status *out);
/** Whether a run in status s is over (finished or failed): it grows no more. */
static inline int sylva_run_status_over(sylva_run_status s) {
  return s == SYLVA_RUN_FINISHED || s == SYLVA_RUN_FAILED;
}

#endif
