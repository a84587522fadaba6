/* sylva server: what the daemon does with each protocol message (protocol.md). */
#ifndef SYLVA_SERVER_HANDLERS_H
#define SYLVA_SERVER_HANDLERS_H

#include "client.h"

/** Handles one complete text message of a client. A bad message gets an `error`
 *  reply and changes nothing. */
void handle_message(client *c, const char *text, size_t len);
/** The same for the client's complete message (c->rx) of DAEMON_PARSE_INLINE
 *  bytes or more: parsed on a libuv thread, handled on the loop once parsed; the
 *  client's later messages wait until then. */
void handle_message_later(client *c);

#endif
