#include "strbuf.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/encode.h"

bool sylva__strbuf_reserve(sylva__strbuf *b, size_t extra) {
  if (b->failed) return false;
  if (extra > SIZE_MAX - b->len - 1) {
    b->failed = true;
    return false;
  }
  size_t need = b->len + extra + 1;
  if (need <= b->cap) return true;
  size_t cap = b->cap ? b->cap : 64;
  while (cap < need) cap = cap > SIZE_MAX / 2 ? need : cap * 2;
  char *data = realloc(b->data, cap);
  if (!data) {
    b->failed = true;
    return false;
  }
  b->data = data;
  b->cap = cap;
  return true;
}

void sylva__strbuf_append(sylva__strbuf *b, const char *s, size_t n) {
  if (!sylva__strbuf_reserve(b, n)) return;
  memcpy(b->data + b->len, s, n);
  b->len += n;
  b->data[b->len] = '\0';
}

void sylva__strbuf_puts(sylva__strbuf *b, const char *s) { sylva__strbuf_append(b, s, strlen(s)); }

void sylva__strbuf_putc(sylva__strbuf *b, char c) { sylva__strbuf_append(b, &c, 1); }

void sylva__strbuf_printf(sylva__strbuf *b, const char *fmt, ...) {
  if (b->failed) return;
  va_list ap;
  va_start(ap, fmt);
  char small[128];
  int n = vsnprintf(small, sizeof small, fmt, ap);
  va_end(ap);
  if (n < 0) {
    b->failed = true;
    return;
  }
  if ((size_t)n < sizeof small) {
    sylva__strbuf_append(b, small, (size_t)n);
    return;
  }
  if (!sylva__strbuf_reserve(b, (size_t)n)) return;
  va_start(ap, fmt);
  vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  b->len += (size_t)n;
}

/* Length of the valid UTF-8 sequence at p (lead byte >= 0x80), 0 if invalid. */
static size_t utf8_length(const unsigned char *p) {
  size_t n;
  uint32_t cp, min;
  if (p[0] >= 0xC2 && p[0] <= 0xDF) n = 2, cp = p[0] & 0x1Fu, min = 0x80;
  else if (p[0] >= 0xE0 && p[0] <= 0xEF) n = 3, cp = p[0] & 0x0Fu, min = 0x800;
  else if (p[0] >= 0xF0 && p[0] <= 0xF4) n = 4, cp = p[0] & 0x07u, min = 0x10000;
  else return 0;
  for (size_t i = 1; i < n; i++) {
    if ((p[i] & 0xC0) != 0x80) return 0; /* also stops at the NUL */
    cp = (cp << 6) | (p[i] & 0x3Fu);
  }
  if (cp < min || (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return 0;
  return n;
}

void sylva__strbuf_json_string(sylva__strbuf *b, const char *s) {
  static const char hex[] = "0123456789abcdef";
  sylva__strbuf_putc(b, '"');
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p >= 0x80) {
      /* Invalid UTF-8 (a message cut in the middle of a character) becomes U+FFFD,
       * so that the output is always valid JSON text. */
      size_t n = utf8_length(p);
      if (n == 0) {
        sylva__strbuf_append(b, "\\ufffd", 6);
      } else {
        sylva__strbuf_append(b, (const char *)p, n);
        p += n - 1;
      }
      continue;
    }
    switch (*p) {
    case '"': sylva__strbuf_append(b, "\\\"", 2); break;
    case '\\': sylva__strbuf_append(b, "\\\\", 2); break;
    case '\b': sylva__strbuf_append(b, "\\b", 2); break;
    case '\f': sylva__strbuf_append(b, "\\f", 2); break;
    case '\n': sylva__strbuf_append(b, "\\n", 2); break;
    case '\r': sylva__strbuf_append(b, "\\r", 2); break;
    case '\t': sylva__strbuf_append(b, "\\t", 2); break;
    default:
      if (*p < 0x20) {
        char esc[6] = {'\\', 'u', '0', '0', hex[*p >> 4], hex[*p & 15]};
        sylva__strbuf_append(b, esc, 6);
      } else {
        sylva__strbuf_putc(b, (char)*p);
      }
    }
  }
  sylva__strbuf_putc(b, '"');
}

void sylva__strbuf_fixed(sylva__strbuf *b, double v, int decimals) {
  char buf[SYLVA_FMT_BUFSIZE];
  sylva_fmt_fixed(buf, sizeof buf, v, decimals);
  sylva__strbuf_puts(b, buf);
}

void sylva__strbuf_shortest(sylva__strbuf *b, double v) {
  char buf[SYLVA_FMT_BUFSIZE];
  sylva_fmt_shortest(buf, sizeof buf, v);
  sylva__strbuf_puts(b, buf);
}

char *sylva__strbuf_finish(sylva__strbuf *b) {
  if (!b->failed && !b->data) sylva__strbuf_reserve(b, 0);
  if (b->failed) {
    sylva__strbuf_free(b);
    return NULL;
  }
  b->data[b->len] = '\0';
  char *out = b->data;
  b->data = NULL;
  b->len = b->cap = 0;
  return out;
}

void sylva__strbuf_free(sylva__strbuf *b) {
  free(b->data);
  b->data = NULL;
  b->len = b->cap = 0;
  b->failed = false;
}
