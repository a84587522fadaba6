/* sylva server: the daemon's shade layer (GET /api/runs/NAME/shade): a day's tree
 * shade on a stored iteration's ground and solid faces (server/shade), as compact
 * JSON for the viewer (docs/protocol.md, "HTTP routes"). */
#ifndef SYLVA_SERVER_SHADE_JSON_H
#define SYLVA_SERVER_SHADE_JSON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "shade.h"
#include "store.h"

/** What the route asks: the run's iteration and the day's window. */
typedef struct shade_request {
  int64_t run;
  int iteration;
  int month, day;  /**< the date (a valid date of a common year) */
  int from, to;    /**< minutes after midnight, from < to */
} shade_request;

/** The defaults of the route: 07-21, 10:00 to 16:00 (iteration and run unset). */
shade_request shade_request_default(void);

/** Reads one "key=value" parameter (key: date, from or to; the iteration is the
 *  caller's) into q. Returns 0, or SERVER_EINPUT with a message naming the
 *  parameter in err ("date: ..."). */
int shade_request_arg(shade_request *q, const char *key, const char *value, char *err,
                      size_t errlen);

/** Checks the parameters together: SERVER_EINPUT ("to: ...") when `to` is not after
 *  `from`. */
int shade_request_check(const shade_request *q, char *err, size_t errlen);

/** Writes the JSON of q into f: the run's scenario gives the site (its light's
 *  latitude, north and clock), st regrows the world at the iteration, shade_compute
 *  gives the sun hours, and each cell's value is the hours of shade the plants add
 *  (open - with). Off the loop thread. Returns 0; SERVER_EINPUT when the run's
 *  light has no site (err says so); SERVER_EFAIL, SERVER_ENOMEM or SERVER_EWRITE
 *  otherwise. */
int shade_json_write(FILE *f, store *st, const shade_request *q, char *err, size_t errlen);

#endif
