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

msgbuf *msgbuf_with_ref(const msgbuf *m, const char *ref) {
  const char *text = (const char *)m->data + LWS_PRE;
  size_t head = m->len - 1, nref = strlen(ref); /* all but the closing brace */
  msgbuf *out = malloc(sizeof *out + LWS_PRE + head + 7 + nref + 1);
  if (!out) return NULL;
  out->refs = 1;
  out->len = head + 7 + nref + 1;
  unsigned char *p = out->data + LWS_PRE;
  memcpy(p, text, head);
  memcpy(p + head, ",\"ref\":", 7);
  memcpy(p + head + 7, ref, nref);
  p[head + 7 + nref] = '}';
  return out;
}

msgbuf *msgbuf_ref(msgbuf *m) {
  m->refs++;
  return m;
}

void msgbuf_unref(msgbuf *m) {
  if (m && --m->refs == 0) free(m);
}
