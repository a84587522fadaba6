/* sylva server: the WebSocket clients. The set of connected clients (its list, its
 * limits, its counters and the timer that applies closes), and each client: its
 * outgoing queue of shared buffers (capped), the reassembly of its incoming
 * message, its rate window, its subscriptions. Loop thread only. */
#ifndef SYLVA_SERVER_CLIENT_H
#define SYLVA_SERVER_CLIENT_H

#include <libwebsockets.h>
#include <stdbool.h>
#include <stdint.h>
#include <uv.h>

#include "msgbuf.h"
#include "sylva/protocol.h"

typedef struct server server;
typedef struct client client;

/** How long a close may wait for the client's queued messages to leave, ms. */
#define CLIENT_FLUSH_MS 1000
/** Clients read at once while their message takes more than one read: the others
 *  wait their turn unread (client.c), so that a turn of the loop reads at most
 *  this many long messages however many clients send one. */
#define CLIENT_READERS 64

/** The limits every client is held to. */
typedef struct client_limits {
  size_t max_message;   /**< bytes of one message */
  size_t max_pending;   /**< bytes waiting to be sent to one client behind the message
                             going out (client_send) */
  int rate_limit;       /**< messages per second */
  int max_clients;      /**< WebSockets at once */
  size_t max_input;     /**< bytes of unfinished messages of all clients together */
  int message_ms;       /**< time a message may take to arrive, from its first frame */
} client_limits;

/** Every connected client, the limits they share and their counters. */
typedef struct client_set {
  client *head;
  int64_t count;                  /**< clients connected now */
  int64_t bytes_sent, messages_received;
  size_t input;                   /**< bytes of unfinished messages now */
  int readers;                    /**< clients reading a long message now */
  client *wait_head, *wait_tail;  /**< clients waiting to read theirs, first first */
  bool trim;                      /**< large receive buffers were freed: give the
                                       memory back to the system (client.c) */
  client_limits limits;
  uv_timer_t closer; /**< applies the closes asked for, outside lws callbacks */
  uv_timer_t watch;  /**< once a second: closes clients whose message is overdue */
} client_set;

/** Starts an empty set on the loop. */
int client_set_init(client_set *s, uv_loop_t *loop, const client_limits *limits);
/** Whether another client may connect. */
bool client_set_has_room(const client_set *s);
/** Asks every client to close (code and reason). */
void client_set_close_all(client_set *s, int code, const char *reason);
/** Closes the set's handle (when the loop winds down; the clients are gone). */
void client_set_close(client_set *s);
/** Clients waiting for a reader's place (CLIENT_READERS). */
int client_set_waiting(const client_set *s);
/** The client with this serial, or NULL. */
client *client_find(client_set *s, uint64_t serial);

/** A client's subscription to a run. */
typedef struct subscription {
  int64_t run;
  bool need_snapshot; /**< send a snapshot (not the next delta) when there is one */
  sylva_detail detail; /**< the detail of its snapshots and deltas */
  char *ref;          /**< the subscribe's id, for that snapshot (malloc'd), or NULL */
} subscription;

struct client {
  client_set *set;
  server *d;            /**< the daemon it talks to, for the message handlers */
  struct lws *wsi;
  uint64_t serial;      /**< unique for the daemon's life; finds a client again later */
  bool authed;
  int token_failures;   /**< wrong hellos so far */
  msgbuf **queue;       /**< ring of messages waiting to be sent */
  size_t qhead, qlen, qcap, pending;
  size_t sent;          /**< bytes of the message at the head already written */
  char *rx;             /**< the message being received */
  size_t rx_len, rx_cap;
  uint64_t rx_start;    /**< when its first frame came (loop ms); 0: none unfinished */
  bool rx_binary, rx_too_large;
  bool reading;         /**< holds one of the CLIENT_READERS places */
  bool waiting;         /**< in the set's queue for one, read no more until then */
  client *wait_next;
  int window_count;     /**< messages in the current one-second window */
  uint64_t window_start;
  subscription *subs;
  size_t nsubs, subs_cap;
  int close_code;       /**< non-zero: close with this code from the loop */
  uint64_t close_after; /**< non-zero: the close waits for the queue to empty, at
                             most until this loop time (ms) */
  char close_reason[96];
  bool refused;         /**< closed for what it sent: read no more, and dropped
                             soon after its close frame (client.c) */
  uint64_t asked_at;    /**< when the close was asked of lws (loop ms) */
  client *next, *prev;
};

/** Starts client c (lws's per-session memory) in the set: zeroed, linked, a new
 *  serial. */
void client_open(client_set *s, client *c, struct lws *wsi, server *d, bool authed);
/** Unlinks a closed client and frees what it holds (not c: lws owns it). */
void client_closed(client *c);
/** Takes one received fragment. Returns true when it completes a text message
 *  within the limits (then c->rx holds it, c->rx_len bytes, until client_handled);
 *  a message too large (for the client or for the input budget of all clients),
 *  too frequent or binary is answered here (closed, or an error) and gives false. */
bool client_receive(client *c, const void *in, size_t len);
/** The message in c->rx has been handled: its bytes leave the input budget. */
void client_handled(client *c);
/** Takes the complete message out of the client (malloc'd, *len bytes, NUL-ended)
 *  to be handled later, and stops reading from the client until client_resume,
 *  so that its messages stay in order. Its bytes still count as input until
 *  client_set_input_done. */
char *client_take_message(client *c, size_t *len);
/** Reads from the client again after client_take_message. */
void client_resume(client *c);
/** A taken message of len bytes is handled (its client may be gone). */
void client_set_input_done(client_set *s, size_t len);

/** Queues a shared message for the client (takes a reference). A client whose
 *  pending output passes the cap is closed (1008, too slow). */
void client_send(client *c, msgbuf *m);
/** Queues malloc'd text (takes it; NULL means out of memory and sends an error). */
void client_send_text(client *c, char *text);
/** Asks for the client to be closed with a code and reason, from the loop (lws
 *  ignores closes asked from inside some of its callbacks). */
void client_close(client *c, int code, const char *reason);
/** The same once the messages queued for the client have been sent (at most
 *  CLIENT_FLUSH_MS later): a refusal's earlier answers are not lost. */
void client_close_after_sending(client *c, int code, const char *reason);
/** Writes one queued message; called on LWS_CALLBACK_SERVER_WRITEABLE. */
int client_writable(client *c);
/** The subscription of c to run, or NULL. */
subscription *client_subscription(client *c, int64_t run);
/** Adds (or finds) a subscription; NULL when out of memory. */
subscription *client_subscribe(client *c, int64_t run);
/** Removes a subscription if there is one. */
void client_unsubscribe(client *c, int64_t run);
#endif
