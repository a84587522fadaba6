/* sylva server: JSON Patch (RFC 6902) on cJSON documents, with JSON Pointers (RFC
 * 6901). A sweep's variants are patches of its scenario (docs/cli.md, "sweep"). */
#ifndef SYLVA_SERVER_JSON_PATCH_H
#define SYLVA_SERVER_JSON_PATCH_H

#include <stddef.h>

#include <cjson/cJSON.h>

/** Applies a patch (an array of operations: add, remove, replace, move, copy,
 *  test) to *doc, in order. On success *doc is the patched document (it may be a
 *  new one: an operation on the pointer "" replaces the whole document). On failure
 *  *doc is unchanged and err says which operation failed and why, e.g.
 *  "2: remove /obstacles/7: /obstacles has 3 elements" (the operation's index). */
int json_patch_apply(cJSON **doc, const cJSON *patch, char *err, size_t errlen);

#endif
