/* sylva server: a message encoded once and shared by every client it goes to,
 * with the headroom libwebsockets wants in front of what it writes. */
#ifndef SYLVA_SERVER_MSGBUF_H
#define SYLVA_SERVER_MSGBUF_H

#include <stddef.h>

/** A shared, reference-counted message (loop thread only). */
typedef struct msgbuf {
  int refs;
  size_t len;
  unsigned char data[]; /* LWS_PRE bytes of headroom, then len bytes */
} msgbuf;

/** Wraps text (len bytes) in a new shared buffer with one reference; NULL when
 *  memory ran out. */
msgbuf *msgbuf_new(const char *text, size_t len);
/** A new buffer holding the JSON object of m with "ref": ref added as its last
 *  member (ref is JSON text), exactly what the encoder writes for a message with
 *  a ref; NULL when memory ran out. */
msgbuf *msgbuf_with_ref(const msgbuf *m, const char *ref);
/** Takes a reference. */
msgbuf *msgbuf_ref(msgbuf *m);
/** Drops a reference (NULL is fine); the last one frees the buffer. */
void msgbuf_unref(msgbuf *m);

#endif
