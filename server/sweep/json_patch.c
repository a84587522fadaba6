/* JSON Patch (RFC 6902) over cJSON: each operation is applied to a copy of the
 * document, which replaces it only when every operation succeeded. */
#include "json_patch.h"

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TOKEN_MAX 1024

/* The next reference token of pointer p (after its '/'), unescaped (~1 is '/', ~0
 * is '~'); *p moves past it. false for a bad escape or a token too long. */
static bool next_token(const char **p, char tok[TOKEN_MAX]) {
  const char *s = *p + 1; /* past '/' */
  size_t n = 0;
  for (; *s && *s != '/'; s++) {
    char c = *s;
    if (c == '~') {
      if (s[1] == '0') c = '~';
      else if (s[1] == '1') c = '/';
      else return false;
      s++;
    }
    if (n + 1 >= TOKEN_MAX) return false;
    tok[n++] = c;
  }
  tok[n] = '\0';
  *p = s;
  return true;
}

/* An array index token: "0" or digits without a leading zero. -1 when it is not. */
static int index_of(const char *tok) {
  size_t n = strlen(tok);
  if (n == 0 || n > 9 || (n > 1 && tok[0] == '0')) return -1;
  for (size_t i = 0; i < n; i++)
    if (tok[i] < '0' || tok[i] > '9') return -1;
  return atoi(tok);
}

/* Where a pointer leads: the container that holds its last token, and that token.
 * *parent is NULL for the pointer "" (the whole document). */
typedef struct place {
  cJSON *parent;
  char last[TOKEN_MAX];
} place;

static bool locate(cJSON *doc, const char *ptr, place *out, char *err, size_t n) {
  out->parent = NULL;
  out->last[0] = '\0';
  if (ptr[0] == '\0') return true;
  if (ptr[0] != '/') {
    snprintf(err, n, "\"%.200s\" is not a JSON pointer (it must be empty or start with /)", ptr);
    return false;
  }
  cJSON *at = doc;
  const char *p = ptr;
  char tok[TOKEN_MAX];
  for (;;) {
    const char *start = p;
    if (!next_token(&p, tok)) {
      snprintf(err, n, "%.200s: a bad ~ escape or a token too long", ptr);
      return false;
    }
    if (*p == '\0') { /* the last token: its container is at */
      if (!cJSON_IsObject(at) && !cJSON_IsArray(at)) {
        snprintf(err, n, "%.*s is not an object or an array", (int)(start - ptr), ptr);
        return false;
      }
      out->parent = at;
      memcpy(out->last, tok, sizeof tok);
      return true;
    }
    cJSON *next = NULL;
    if (cJSON_IsObject(at)) {
      next = cJSON_GetObjectItemCaseSensitive(at, tok);
    } else if (cJSON_IsArray(at)) {
      int i = index_of(tok);
      if (i >= 0) next = cJSON_GetArrayItem(at, i);
    }
    if (!next) {
      snprintf(err, n, "%.*s does not exist", (int)(p - ptr), ptr);
      return false;
    }
    at = next;
  }
}

/* The value a place holds (NULL when there is none). */
static cJSON *value_at(cJSON *doc, const place *pl) {
  if (!pl->parent) return doc;
  if (cJSON_IsObject(pl->parent)) return cJSON_GetObjectItemCaseSensitive(pl->parent, pl->last);
  int i = index_of(pl->last);
  return i >= 0 ? cJSON_GetArrayItem(pl->parent, i) : NULL;
}

static bool exists(cJSON *doc, const char *ptr, const place *pl, char *err, size_t n) {
  if (value_at(doc, pl)) return true;
  if (cJSON_IsArray(pl->parent))
    snprintf(err, n, "%.200s does not exist (the array has %d elements)", ptr,
             cJSON_GetArraySize(pl->parent));
  else
    snprintf(err, n, "%.200s does not exist", ptr);
  return false;
}

/* Adds v (owned) at a place: replaces the document, sets an object's member, or
 * inserts into an array (at an index up to its size, or "-": at its end). */
static bool add_at(cJSON **doc, const char *ptr, const place *pl, cJSON *v, char *err,
                   size_t n) {
  if (!pl->parent) {
    cJSON_Delete(*doc);
    *doc = v;
    return true;
  }
  if (cJSON_IsObject(pl->parent)) {
    if (cJSON_GetObjectItemCaseSensitive(pl->parent, pl->last))
      return cJSON_ReplaceItemInObjectCaseSensitive(pl->parent, pl->last, v) ||
             (cJSON_Delete(v), false);
    return cJSON_AddItemToObject(pl->parent, pl->last, v) || (cJSON_Delete(v), false);
  }
  int size = cJSON_GetArraySize(pl->parent);
  int i = strcmp(pl->last, "-") == 0 ? size : index_of(pl->last);
  if (i < 0 || i > size) {
    snprintf(err, n, "%.200s: no place %s in an array of %d elements", ptr, pl->last, size);
    cJSON_Delete(v);
    return false;
  }
  /* Debian 12's cJSON_InsertItemInArray (1.7.15-1+deb12u4) inserts nothing and
   * returns false before any existing element: move the tail aside, append, and
   * put the tail back */
  cJSON *tail = cJSON_CreateArray();
  if (!tail) {
    cJSON_Delete(v);
    snprintf(err, n, "out of memory");
    return false;
  }
  while (cJSON_GetArraySize(pl->parent) > i)
    cJSON_AddItemToArray(tail, cJSON_DetachItemFromArray(pl->parent, i));
  cJSON_AddItemToArray(pl->parent, v);
  while (tail->child) cJSON_AddItemToArray(pl->parent, cJSON_DetachItemFromArray(tail, 0));
  cJSON_Delete(tail);
  return true;
}

/* Takes the value at an existing place out of the document (the caller owns it). */
static cJSON *detach_at(const place *pl) {
  if (cJSON_IsObject(pl->parent))
    return cJSON_DetachItemFromObjectCaseSensitive(pl->parent, pl->last);
  return cJSON_DetachItemFromArray(pl->parent, index_of(pl->last));
}

static const char *member(const cJSON *op, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(op, key);
  return cJSON_IsString(v) ? v->valuestring : NULL;
}

/* Applies one operation to *doc. */
static bool apply_one(cJSON **doc, const cJSON *op, char *err, size_t n) {
  const char *name = member(op, "op"), *path = member(op, "path");
  if (!cJSON_IsObject(op) || !name || !path) {
    snprintf(err, n, "an operation is an object with the strings \"op\" and \"path\"");
    return false;
  }
  const cJSON *value = cJSON_GetObjectItemCaseSensitive(op, "value");
  const char *from = member(op, "from");
  bool is_add = strcmp(name, "add") == 0, is_replace = strcmp(name, "replace") == 0,
       is_test = strcmp(name, "test") == 0, is_move = strcmp(name, "move") == 0,
       is_copy = strcmp(name, "copy") == 0;
  if (!is_add && !is_replace && !is_test && !is_move && !is_copy && strcmp(name, "remove")) {
    snprintf(err, n, "unknown op \"%.40s\" (add, remove, replace, move, copy, test)", name);
    return false;
  }
  if ((is_add || is_replace || is_test) && !value) {
    snprintf(err, n, "%s %.200s: no \"value\"", name, path);
    return false;
  }
  if ((is_move || is_copy) && !from) {
    snprintf(err, n, "%s %.200s: no \"from\" string", name, path);
    return false;
  }
  char why[600];
  place pl;
  bool ok = locate(*doc, path, &pl, why, sizeof why);
  if (ok && (is_move || is_copy)) {
    place src;
    size_t fl = strlen(from);
    if (is_move && strncmp(path, from, fl) == 0 && path[fl] == '/') {
      snprintf(why, sizeof why, "cannot move %.200s into itself", from);
      ok = false;
    } else if ((ok = locate(*doc, from, &src, why, sizeof why) &&
                     exists(*doc, from, &src, why, sizeof why))) {
      if (is_move && strcmp(path, from) == 0) {
        snprintf(err, n, "%s", ""); /* moving a value onto itself changes nothing */
        return true;
      }
      cJSON *v = is_copy ? cJSON_Duplicate(value_at(*doc, &src), true) : NULL;
      if (is_move) {
        if (!src.parent) {
          snprintf(why, sizeof why, "cannot move the whole document");
          ok = false;
        } else {
          v = detach_at(&src);
          /* the target's place may have shifted: find it again */
          ok = locate(*doc, path, &pl, why, sizeof why);
        }
      }
      if (ok) ok = v && add_at(doc, path, &pl, v, why, sizeof why);
      else cJSON_Delete(v);
    }
  } else if (ok && is_add) {
    cJSON *v = cJSON_Duplicate(value, true);
    ok = v && add_at(doc, path, &pl, v, why, sizeof why);
  } else if (ok) { /* remove, replace and test need the value to exist */
    ok = exists(*doc, path, &pl, why, sizeof why);
    if (ok && is_test) {
      if (!cJSON_Compare(value_at(*doc, &pl), value, true)) {
        snprintf(why, sizeof why, "%.200s is not the value the test expects", path);
        ok = false;
      }
    } else if (ok && is_replace) {
      cJSON *v = cJSON_Duplicate(value, true);
      if (!pl.parent) {
        ok = v != NULL;
        if (ok) {
          cJSON_Delete(*doc);
          *doc = v;
        }
      } else if (!v) {
        snprintf(why, sizeof why, "out of memory");
        ok = false;
      } else if (cJSON_IsObject(pl.parent)) { /* in place: the members keep their order */
        ok = cJSON_ReplaceItemInObjectCaseSensitive(pl.parent, pl.last, v) ||
             (cJSON_Delete(v), false);
      } else {
        ok = cJSON_ReplaceItemInArray(pl.parent, index_of(pl.last), v) ||
             (cJSON_Delete(v), false);
      }
    } else if (ok) {
      if (!pl.parent) {
        snprintf(why, sizeof why, "cannot remove the whole document");
        ok = false;
      } else {
        cJSON_Delete(detach_at(&pl));
      }
    }
  }
  if (!ok) snprintf(err, n, "%.16s %.200s: %.500s", name, path, why);
  return ok;
}

int json_patch_apply(cJSON **doc, const cJSON *patch, char *err, size_t errlen) {
  if (!cJSON_IsArray(patch)) {
    snprintf(err, errlen, "a patch is an array of operations");
    return -1;
  }
  cJSON *copy = cJSON_Duplicate(*doc, true);
  if (!copy) {
    snprintf(err, errlen, "out of memory");
    return -1;
  }
  int i = 0;
  const cJSON *op;
  cJSON_ArrayForEach(op, patch) {
    char why[1024];
    if (!apply_one(&copy, op, why, sizeof why)) {
      snprintf(err, errlen, "%d: %s", i, why);
      cJSON_Delete(copy);
      return -1;
    }
    i++;
  }
  cJSON_Delete(*doc);
  *doc = copy;
  return 0;
}
