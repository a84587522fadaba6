/* A strict RFC 8259 checker: an iterative state machine, so that deep nesting
 * costs one byte of stack per level and never recursion. */
#include "sylva/json_check.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "sylva/status.h"

typedef struct checker {
  const unsigned char *s;
  size_t len, pos;
  unsigned flags;
  char *err;
  size_t errlen;
} checker;

/* Writes "line L, column C (byte B): message"; columns count UTF-8 characters. */
static int fail_at(checker *c, size_t at, const char *fmt, ...) {
  if (!c->err || c->errlen == 0) return SYLVA_EINVAL;
  size_t line = 1, column = 1;
  for (size_t i = 0; i < at && i < c->len; i++) {
    if (c->s[i] == '\n') {
      line++;
      column = 1;
    } else if ((c->s[i] & 0xC0) != 0x80) {
      column++;
    }
  }
  int n = snprintf(c->err, c->errlen, "line %zu, column %zu (byte %zu): ", line, column, at);
  if (n >= 0 && (size_t)n < c->errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->err + n, c->errlen - (size_t)n, fmt, ap);
    va_end(ap);
  }
  return SYLVA_EINVAL;
}

/* Describes the byte at pos for a message: "end of input", "'x'" or "byte 0x0C". */
static const char *describe(const checker *c, size_t pos, char buf[16]) {
  if (pos >= c->len) return "end of input";
  unsigned char b = c->s[pos];
  if (b > 0x20 && b < 0x7F) {
    snprintf(buf, 16, "'%c'", b);
  } else {
    snprintf(buf, 16, "byte 0x%02X", b);
  }
  return buf;
}

static void skip_ws(checker *c) {
  while (c->pos < c->len) {
    unsigned char b = c->s[c->pos];
    if (b != ' ' && b != '\t' && b != '\n' && b != '\r') break;
    c->pos++;
  }
}

static bool is_digit(unsigned char b) { return b >= '0' && b <= '9'; }

static int hex4(const checker *c, size_t pos) {
  if (pos + 4 > c->len) return -1;
  int v = 0;
  for (size_t i = pos; i < pos + 4; i++) {
    unsigned char b = c->s[i];
    int d;
    if (b >= '0' && b <= '9') d = b - '0';
    else if (b >= 'a' && b <= 'f') d = b - 'a' + 10;
    else if (b >= 'A' && b <= 'F') d = b - 'A' + 10;
    else return -1;
    v = v * 16 + d;
  }
  return v;
}

static int check_number(checker *c) {
  size_t start = c->pos;
  if (c->s[c->pos] == '-') c->pos++;
  if (c->pos >= c->len || !is_digit(c->s[c->pos]))
    return fail_at(c, c->pos, "'-' must be followed by a digit");
  if (c->s[c->pos] == '0') {
    c->pos++;
    if (c->pos < c->len && is_digit(c->s[c->pos])) return fail_at(c, start, "leading zero in number");
  } else {
    while (c->pos < c->len && is_digit(c->s[c->pos])) c->pos++;
  }
  if (c->pos < c->len && c->s[c->pos] == '.') {
    c->pos++;
    if (c->pos >= c->len || !is_digit(c->s[c->pos]))
      return fail_at(c, c->pos, "digit expected after the decimal point");
    while (c->pos < c->len && is_digit(c->s[c->pos])) c->pos++;
  }
  if (c->pos < c->len && (c->s[c->pos] == 'e' || c->s[c->pos] == 'E')) {
    c->pos++;
    if (c->pos < c->len && (c->s[c->pos] == '+' || c->s[c->pos] == '-')) c->pos++;
    if (c->pos >= c->len || !is_digit(c->s[c->pos]))
      return fail_at(c, c->pos, "digit expected in the exponent");
    while (c->pos < c->len && is_digit(c->s[c->pos])) c->pos++;
  }
  if ((c->flags & SYLVA_JSON_CJSON_NUMBERS) && c->pos - start > SYLVA_JSON_CJSON_NUMBER_MAX)
    return fail_at(c, start, "number of %zu characters; at most %d are supported", c->pos - start,
                   SYLVA_JSON_CJSON_NUMBER_MAX);
  return 0;
}

/* One UTF-8 sequence of two to four bytes at c->pos (the lead byte is >= 0x80). */
static int check_utf8(checker *c) {
  size_t at = c->pos;
  unsigned char b = c->s[at];
  int n;
  uint32_t cp, min;
  if (b >= 0xC0 && b <= 0xDF) {
    n = 2, cp = b & 0x1Fu, min = 0x80;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3, cp = b & 0x0Fu, min = 0x800;
  } else if (b >= 0xF0 && b <= 0xF7) {
    n = 4, cp = b & 0x07u, min = 0x10000;
  } else if (b >= 0x80 && b <= 0xBF) {
    return fail_at(c, at, "invalid UTF-8: unexpected continuation byte 0x%02X", b);
  } else {
    return fail_at(c, at, "invalid UTF-8: byte 0x%02X", b);
  }
  for (int i = 1; i < n; i++) {
    if (at + (size_t)i >= c->len || (c->s[at + (size_t)i] & 0xC0) != 0x80)
      return fail_at(c, at, "invalid UTF-8: truncated %d-byte sequence", n);
    cp = (cp << 6) | (c->s[at + (size_t)i] & 0x3Fu);
  }
  if (cp < min) return fail_at(c, at, "invalid UTF-8: overlong encoding of U+%04X", (unsigned)cp);
  if (cp >= 0xD800 && cp <= 0xDFFF)
    return fail_at(c, at, "invalid UTF-8: encoded surrogate U+%04X", (unsigned)cp);
  if (cp > 0x10FFFF) return fail_at(c, at, "invalid UTF-8: code point above U+10FFFF");
  c->pos = at + (size_t)n;
  return 0;
}

static int check_string(checker *c) {
  size_t start = c->pos++;
  for (;;) {
    if (c->pos >= c->len) return fail_at(c, start, "unterminated string");
    unsigned char b = c->s[c->pos];
    if (b == '"') {
      c->pos++;
      return 0;
    }
    if (b < 0x20) return fail_at(c, c->pos, "control character U+%04X must be escaped in a string", b);
    if (b >= 0x80) {
      int rc = check_utf8(c);
      if (rc) return rc;
      continue;
    }
    if (b != '\\') {
      c->pos++;
      continue;
    }
    size_t esc = c->pos++;
    if (c->pos >= c->len) return fail_at(c, start, "unterminated string");
    unsigned char e = c->s[c->pos];
    if (e == '"' || e == '\\' || e == '/' || e == 'b' || e == 'f' || e == 'n' || e == 'r' ||
        e == 't') {
      c->pos++;
      continue;
    }
    if (e != 'u') {
      char buf[16];
      return fail_at(c, esc, "invalid escape: backslash followed by %s", describe(c, c->pos, buf));
    }
    int cp = hex4(c, c->pos + 1);
    if (cp < 0) return fail_at(c, esc, "\\u must be followed by four hex digits");
    c->pos += 5;
    /* Unpaired surrogate escapes are rejected (RFC 8259 leaves them to the
     * parser): they name no character, cannot be written as UTF-8, and cJSON
     * would turn them into an error or garbage; our labels must re-serialise as
     * valid UTF-8. */
    if (cp >= 0xDC00 && cp <= 0xDFFF)
      return fail_at(c, esc, "unpaired surrogate escape \\u%04X", (unsigned)cp);
    if (cp >= 0xD800 && cp <= 0xDBFF) {
      int lo = -1;
      if (c->pos + 1 < c->len && c->s[c->pos] == '\\' && c->s[c->pos + 1] == 'u')
        lo = hex4(c, c->pos + 2);
      if (lo < 0xDC00 || lo > 0xDFFF)
        return fail_at(c, esc, "unpaired surrogate escape \\u%04X", (unsigned)cp);
      c->pos += 6;
    } else if (cp == 0 && (c->flags & SYLVA_JSON_NO_NUL_ESCAPE)) {
      return fail_at(c, esc, "\\u0000 (NUL) is not allowed in strings here");
    }
  }
}

static int check_literal(checker *c) {
  static const char *const words[] = {"true", "false", "null"};
  for (int i = 0; i < 3; i++) {
    if (c->s[c->pos] != (unsigned char)words[i][0]) continue;
    size_t n = 0;
    while (words[i][n] != '\0') {
      if (c->pos + n >= c->len || c->s[c->pos + n] != (unsigned char)words[i][n])
        return fail_at(c, c->pos, "invalid literal (expected %s)", words[i]);
      n++;
    }
    c->pos += n;
    return 0;
  }
  char buf[16];
  return fail_at(c, c->pos, "expected a value, got %s", describe(c, c->pos, buf));
}

int sylva_json_check_ex(const char *text, size_t len, int max_depth, unsigned flags, char *err,
                        size_t errlen) {
  checker c = {(const unsigned char *)text, len, 0, flags, err, errlen};
  if (err && errlen) err[0] = '\0';
  if (max_depth > SYLVA_JSON_DEPTH_LIMIT) max_depth = SYLVA_JSON_DEPTH_LIMIT;
  if (max_depth < 0) max_depth = 0;
  /* One byte per open container: 1 for an object, 0 for an array. */
  unsigned char stack[SYLVA_JSON_DEPTH_LIMIT];
  int depth = 0;
  enum { VALUE, KEY, AFTER } state = VALUE;
  char buf[16];
  int rc;

  if (len >= 3 && c.s[0] == 0xEF && c.s[1] == 0xBB && c.s[2] == 0xBF)
    return fail_at(&c, 0, "byte order mark (U+FEFF) before the JSON text");
  skip_ws(&c);
  if (c.pos >= len) return fail_at(&c, c.pos, "empty document: no JSON value");

  for (;;) {
    skip_ws(&c);
    switch (state) {
    case VALUE: {
      if (c.pos >= len) return fail_at(&c, c.pos, "unexpected end of input, expected a value");
      unsigned char b = c.s[c.pos];
      if (b == '{' || b == '[') {
        if (depth >= max_depth) return fail_at(&c, c.pos, "nesting deeper than %d", max_depth);
        stack[depth++] = b == '{';
        c.pos++;
        skip_ws(&c);
        if (c.pos < len && c.s[c.pos] == (b == '{' ? '}' : ']')) {
          c.pos++;
          depth--;
          state = AFTER;
        } else {
          state = b == '{' ? KEY : VALUE;
        }
        continue;
      }
      if (b == '"') rc = check_string(&c);
      else if (b == '-' || is_digit(b)) rc = check_number(&c);
      else rc = check_literal(&c);
      if (rc) return rc;
      state = AFTER;
      continue;
    }
    case KEY:
      if (c.pos >= len) return fail_at(&c, c.pos, "unexpected end of input, expected a key");
      if (c.s[c.pos] != '"')
        return fail_at(&c, c.pos, "expected a string key, got %s", describe(&c, c.pos, buf));
      if ((rc = check_string(&c))) return rc;
      skip_ws(&c);
      if (c.pos >= len || c.s[c.pos] != ':')
        return fail_at(&c, c.pos, "expected ':' after the key, got %s", describe(&c, c.pos, buf));
      c.pos++;
      state = VALUE;
      continue;
    case AFTER: {
      if (depth == 0) {
        if (c.pos == len) return 0;
        return fail_at(&c, c.pos, "unexpected %s after the JSON value", describe(&c, c.pos, buf));
      }
      bool object = stack[depth - 1];
      char close = object ? '}' : ']';
      if (c.pos < len && c.s[c.pos] == close) {
        c.pos++;
        depth--;
        continue;
      }
      if (c.pos >= len || c.s[c.pos] != ',')
        return fail_at(&c, c.pos, "expected ',' or '%c', got %s", close, describe(&c, c.pos, buf));
      c.pos++;
      skip_ws(&c);
      if (c.pos < len && c.s[c.pos] == close)
        return fail_at(&c, c.pos, "trailing comma before '%c'", close);
      state = object ? KEY : VALUE;
      continue;
    }
    }
  }
}

int sylva_utf8_check(const char *text, size_t len, char *err, size_t errlen) {
  checker c = {(const unsigned char *)text, len, 0, 0, err, errlen};
  if (err && errlen) err[0] = '\0';
  while (c.pos < len) {
    if (c.s[c.pos] < 0x80) {
      c.pos++;
    } else {
      int rc = check_utf8(&c);
      if (rc) return rc;
    }
  }
  return 0;
}

int sylva_json_check(const char *text, size_t len, int max_depth, char *err, size_t errlen) {
  return sylva_json_check_ex(text, len, max_depth, 0, err, errlen);
}
