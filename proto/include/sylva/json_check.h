/* sylva: a strict RFC 8259 validator, run before cJSON.
 *
 * cJSON 1.7.15 is lenient (leading zeros, "2.", raw control characters in
 * strings, bad \u escapes, form feed and NUL as whitespace, invalid UTF-8); this
 * checker accepts exactly the JSON texts of RFC 8259, so what reaches cJSON is
 * already known to be well formed. */
#ifndef SYLVA_JSON_CHECK_H
#define SYLVA_JSON_CHECK_H

#include <stddef.h>

/** Deepest nesting the checker can follow; a larger max_depth is clamped to it. */
#define SYLVA_JSON_DEPTH_LIMIT 1000

/** Flags of sylva_json_check_ex(). */
enum {
  /** Also reject "\u0000" in strings: cJSON cuts a string at its first NUL, so a
   *  scenario label "a\u0000b" would silently become "a". */
  SYLVA_JSON_NO_NUL_ESCAPE = 1,
  /** Also reject numbers longer than SYLVA_JSON_CJSON_NUMBER_MAX characters: cJSON
   *  1.7.15 reads at most that many characters of a number and then fails on a
   *  valid text. */
  SYLVA_JSON_CJSON_NUMBERS = 2
};

/** Longest number text cJSON 1.7.15 can read (its buffer of 64 bytes with the NUL). */
#define SYLVA_JSON_CJSON_NUMBER_MAX 63

/** Checks that text[0..len) is valid UTF-8 (RFC 3629: no overlong forms,
 *  surrogates or code points above U+10FFFF). 0, or SYLVA_EINVAL with err saying
 *  where (err may be NULL). */
int sylva_utf8_check(const char *text, size_t len, char *err, size_t errlen);

/** Checks that text[0..len) is exactly one RFC 8259 JSON value surrounded by
 *  optional whitespace (space, tab, LF, CR), in valid UTF-8, with arrays and
 *  objects nested at most max_depth deep (the outermost container is depth 1).
 *  Returns 0, or SYLVA_EINVAL with a message such as
 *  "line 3, column 14 (byte 52): leading zero in number" in err (columns count
 *  characters, from 1; err may be NULL). */
int sylva_json_check(const char *text, size_t len, int max_depth, char *err, size_t errlen);

/** sylva_json_check() with SYLVA_JSON_* flags. */
int sylva_json_check_ex(const char *text, size_t len, int max_depth, unsigned flags, char *err,
                        size_t errlen);

#endif
