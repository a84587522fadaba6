/* sylva server: the one error convention of the store, export and daemon
 * libraries and of the command line. A function that can fail returns SERVER_OK
 * (0) or a negative server_error and says why in its own way (an err buffer, the
 * store's message, stderr); the command line turns the code into its exit status
 * (docs/cli.md, "Exit status"). One X-macro list gives the enum, the names and the
 * exit statuses, as core's sylva/status.h does for the model. */
#ifndef SYLVA_SERVER_ERROR_H
#define SYLVA_SERVER_ERROR_H

/* X(name, value, message, exit status) */
#define SERVER_ERRORS(X)                                                 \
  X(SERVER_OK, 0, "ok", 0)                                               \
  X(SERVER_EFAIL, -1, "failed (the store, the disk or a library)", 1)    \
  X(SERVER_EINPUT, -2, "bad input (no such run or iteration, bad file)", 2) \
  X(SERVER_EWRITE, -3, "cannot write the output", 1)                     \
  X(SERVER_ENOMEM, -4, "out of memory", 1)

typedef enum server_error {
#define SERVER_ERROR_ENUM(name, value, message, exit_status) name = value,
  SERVER_ERRORS(SERVER_ERROR_ENUM)
#undef SERVER_ERROR_ENUM
} server_error;

/** A one-line description of err ("unknown error" for a value not in the list). */
const char *server_strerror(int err);
/** The exit status of the binary for err: 0, 1 (runtime failure) or 2 (bad input). */
int server_exit_status(int err);

#endif
