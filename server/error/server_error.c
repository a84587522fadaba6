#include "server_error.h"

#include <stdarg.h>
#include <stdio.h>

int server_exit_status(int err) {
  switch (err) {
#define SERVER_ERROR_EXIT(name, value, exit_status) \
  case name:                                        \
    return exit_status;
    SERVER_ERRORS(SERVER_ERROR_EXIT)
#undef SERVER_ERROR_EXIT
  }
  return 1;
}

int server_fail(char *err, size_t errlen, int status, const char *fmt, ...) {
  if (err && errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
  }
  return status;
}
