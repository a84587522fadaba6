#include "msgbuf.h"

#include <libwebsockets.h>
#include <stdlib.h>
#include <string.h>

msgbuf *msgbuf_new(const char *text, size_t len) {
  msgbuf *m = malloc(sizeof *m + LWS_PRE + len);
  if (!m) return NULL;
  m->refs = 1;
  m->len = len;
  memcpy(m->data + LWS_PRE, text, len);
  return m;
}

msgbuf *msgbuf_ref(msgbuf *m) {
  m->refs++;
  return m;
}

void msgbuf_unref(msgbuf *m) {
  if (m && --m->refs == 0) free(m);
}
