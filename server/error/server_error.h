/* sylva server: the one error convention of the store, export and daemon
 * libraries and of the command line. A function that can fail returns SERVER_OK
 * (0) or a negative server_error and says why in its own way (an err buffer, the
 * store's message, stderr); the command line turns the code into its exit status
 * (docs/cli.md, "Exit status"). One X-macro list gives the enum and the exit
 * statuses, as core's sylva/status.h does for the model. */
#ifndef SYLVA_SERVER_ERROR_H
#define SYLVA_SERVER_ERROR_H

/* X(name, value, exit status). The message of a failure is always more specific
 * than its code (the store's error, an err buffer naming the file), so the list
 * carries none:
 *   SERVER_EFAIL   the store, the disk or a library failed
 *   SERVER_EINPUT  bad input: no such run or iteration, an unreadable or bad file
 *   SERVER_EWRITE  the output could not be written
 *   SERVER_ENOMEM  out of memory */
#define SERVER_ERRORS(X)   \
  X(SERVER_OK, 0, 0)       \
  X(SERVER_EFAIL, -1, 1)   \
  X(SERVER_EINPUT, -2, 2)  \
  X(SERVER_EWRITE, -3, 1)  \
  X(SERVER_ENOMEM, -4, 1)

typedef enum server_error {
#define SERVER_ERROR_ENUM(name, value, exit_status) name = value,
  SERVER_ERRORS(SERVER_ERROR_ENUM)
#undef SERVER_ERROR_ENUM
} server_error;

/** The exit status of the binary for err: 0, 1 (runtime failure) or 2 (bad input). */
int server_exit_status(int err);

#include <stddef.h>

/** Writes the message into err (when err and errlen) and returns status: an error
 *  said and returned in one statement. */
int server_fail(char *err, size_t errlen, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
