/* A growable NUL-terminated string with a sticky out-of-memory flag: appends
 * after a failed allocation do nothing, so callers check once at the end. */
#ifndef SYLVA_PROTO_STRBUF_H
#define SYLVA_PROTO_STRBUF_H

#include <stdbool.h>
#include <stddef.h>

/** The buffer; zero-initialise it ({0}) before use. */
typedef struct sylva__strbuf {
  char *data;  /**< NUL-terminated once anything was appended */
  size_t len;  /**< bytes, without the NUL */
  size_t cap;  /**< bytes allocated */
  bool failed; /**< an allocation failed; the content is incomplete */
} sylva__strbuf;

/** Makes room for at least extra more bytes (plus the NUL); false on failure. */
bool sylva__strbuf_reserve(sylva__strbuf *b, size_t extra);
/** Appends n bytes. */
void sylva__strbuf_append(sylva__strbuf *b, const char *s, size_t n);
/** Appends a NUL-terminated string. */
void sylva__strbuf_puts(sylva__strbuf *b, const char *s);
/** Appends one byte. */
void sylva__strbuf_putc(sylva__strbuf *b, char c);
/** Appends printf-style formatted text. */
void sylva__strbuf_printf(sylva__strbuf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/** Appends s as a JSON string literal (quotes and escapes included); bytes that are
 *  not valid UTF-8 become U+FFFD. */
void sylva__strbuf_json_string(sylva__strbuf *b, const char *s);
/** Appends a number with sylva_fmt_fixed(). */
void sylva__strbuf_fixed(sylva__strbuf *b, double v, int decimals);
/** Appends a number with sylva_fmt_shortest(). */
void sylva__strbuf_shortest(sylva__strbuf *b, double v);
/** Hands the text over (an empty string if nothing was appended); NULL and the
 *  buffer freed if an allocation failed. The buffer is reset. */
char *sylva__strbuf_finish(sylva__strbuf *b);
/** Frees the buffer and resets it. */
void sylva__strbuf_free(sylva__strbuf *b);

#endif
