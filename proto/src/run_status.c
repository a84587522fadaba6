#include "sylva/run_status.h"

#include <string.h>

static const char *const names[] = {
#define SYLVA_RUN_STATUS_NAME(name, text) [name] = text,
    SYLVA_RUN_STATUSES(SYLVA_RUN_STATUS_NAME)
#undef SYLVA_RUN_STATUS_NAME
};

const char *sylva_run_status_name(sylva_run_status s) {
  return (unsigned)s < sizeof names / sizeof names[0] ? names[s] : "unknown";
}

int sylva_run_status_parse(const char *text, sylva_run_status *out) {
  for (unsigned i = 0; i < sizeof names / sizeof names[0]; i++)
    if (strcmp(text, names[i]) == 0) {
      *out = (sylva_run_status)i;
      return 0;
    }
  return -1;
}
