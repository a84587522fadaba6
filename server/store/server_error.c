#include "server_error.h"

const char *server_strerror(int err) {
  switch (err) {
#define SERVER_ERROR_MESSAGE(name, value, message, exit_status) \
  case name:                                                    \
    return message;
    SERVER_ERRORS(SERVER_ERROR_MESSAGE)
#undef SERVER_ERROR_MESSAGE
  }
  return "unknown error";
}

int server_exit_status(int err) {
  switch (err) {
#define SERVER_ERROR_EXIT(name, value, message, exit_status) \
  case name:                                                 \
    return exit_status;
    SERVER_ERRORS(SERVER_ERROR_EXIT)
#undef SERVER_ERROR_EXIT
  }
  return 1;
}
