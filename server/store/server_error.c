#include "server_error.h"

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
