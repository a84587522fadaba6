/* sylva server: one WebSocket client: its outgoing queue of shared buffers (capped),
 * the reassembly of its incoming message, its rate window, its subscriptions. */
#ifndef SYLVA_SERVER_CLIENT_H
#define SYLVA_SERVER_CLIENT_H

#include "daemon.h"

/** A client's subscription to a run. */
typedef struct subscription {
  int64_t run;
  bool need_snapshot; /**< send a snapshot (not the next delta) when the run is idle */
} subscription;

struct client {
  server *d;
  struct lws *wsi;
  uint64_t serial;      /**< unique for the daemon's life; finds a client again later */
  bool authed;
  msgbuf **queue;       /**< ring of messages waiting to be sent */
  size_t qhead, qlen, qcap, pending;
  size_t sent;          /**< bytes of the message at the head already written */
  char *rx;             /**< the message being received */
  size_t rx_len, rx_cap;
  bool rx_binary, rx_too_large;
  int window_count;     /**< messages in the current one-second window */
  uint64_t window_start;
  subscription *subs;
  size_t nsubs, subs_cap;
  int close_code;       /**< non-zero: close with this code from the loop */
  char close_reason[96];
  client *next, *prev;
};

/** Queues a shared message for the client (takes a reference). A client whose
 *  pending output passes the cap is closed (1008, too slow). */
void client_send(client *c, msgbuf *m);
/** Queues malloc'd text (takes it; NULL means out of memory and sends an error). */
void client_send_text(client *c, char *text);
/** Asks for the client to be closed with a code and reason, from the loop (lws
 *  ignores closes asked from inside some of its callbacks). */
void client_close(client *c, int code, const char *reason);
/** Writes one queued message; called on LWS_CALLBACK_SERVER_WRITEABLE. */
int client_writable(client *c);
/** The subscription of c to run, or NULL. */
subscription *client_subscription(client *c, int64_t run);
/** Adds (or finds) a subscription; NULL when out of memory. */
subscription *client_subscribe(client *c, int64_t run);
/** Removes a subscription if there is one. */
void client_unsubscribe(client *c, int64_t run);
/** Frees everything the client holds (not the client: lws owns it). */
void client_release(client *c);
/** Applies pending closes; called from a libuv callback. */
void clients_close_pending(server *d);
/** The client with this serial, or NULL. */
client *client_find(server *d, uint64_t serial);
#endif
