/* libsylva-import: measured trees. A quantitative structure model (QSM) is a table
 * of cylinders, each with its radius, length, start, axis and parent, as TreeQSM,
 * SimpleForest, aRchi and rTwig write them from laser scans (docs/cli.md, "import").
 * This header holds the cylinder model every reader fills; tree.h turns it into
 * internodes. */
#ifndef SYLVA_IMPORT_QSM_H
#define SYLVA_IMPORT_QSM_H

#include "server_error.h"
#include <stdbool.h>
#include <stddef.h>

/** The formats `sylva import` reads. */
typedef enum sylva_qsm_format {
  SYLVA_QSM_UNKNOWN = 0,
  SYLVA_QSM_MAT,      /**< TreeQSM .mat (2.0 flat variables; 2.3/2.4 QSM structs), libmatio */
  SYLVA_QSM_TEXT,     /**< TreeQSM save_model_text: 17 columns (header row) or 15 (none) */
  SYLVA_QSM_CSV,      /**< SimpleForest CSV: named columns, IDs from 0, root parent -1 */
  SYLVA_QSM_SKELETON, /**< sylva.skeleton/1 JSON */
} sylva_qsm_format;

/** One cylinder. Lengths in metres. parent is a 0-based index into the model's
 *  cylinders, -1 for a root. */
typedef struct sylva_qsm_cylinder {
  double radius, length;
  double start[3], axis[3]; /**< axis: a unit vector */
  int parent;
  int branch;       /**< the file's branch number (0 when the file has none) */
  int branch_order; /**< 0 on the stem (0 when the file has none) */
} sylva_qsm_cylinder;

/** The file's own figures, when it carries them (TreeQSM's treedata). NaN if absent. */
typedef struct sylva_qsm_treedata {
  double height;       /**< TreeHeight, m */
  double dbh;          /**< DBHqsm, m */
  double total_volume; /**< TotalVolume, litres as TreeQSM gives it */
  double total_length; /**< TotalLength, m */
  double branches;     /**< NumberBranches */
  double max_order;    /**< MaxBranchOrder */
} sylva_qsm_treedata;

/** A cylinder model. Owned: free with sylva_qsm_free. */
typedef struct sylva_qsm {
  sylva_qsm_cylinder *cyl;
  size_t count;
  bool has_treedata;
  sylva_qsm_treedata treedata;
  int models; /**< models in the file (a .mat may hold several) */
} sylva_qsm;

/** Frees q's cylinders and zeroes it. */
void sylva_qsm_free(sylva_qsm *q);

/** The format named by s ("mat", "text", "csv", "skeleton"), or UNKNOWN. */
sylva_qsm_format sylva_qsm_format_named(const char *s);
/** The format's name. */
const char *sylva_qsm_format_name(sylva_qsm_format f);
/** The format of the file at path, from its first bytes and its extension. */
sylva_qsm_format sylva_qsm_sniff(const char *path);

/** Reads model `model` (1-based; 0 for the first) of the file at path in format f
 *  (UNKNOWN: sniffed). Returns 0, or a negative status with a message in err naming
 *  what is wrong and where (row, column or field); q is then empty. Checks every
 *  value: finite, radius and length above 0, parents in range and without cycles,
 *  at least one cylinder. */
int sylva_qsm_read(const char *path, sylva_qsm_format f, int model, sylva_qsm *q, char *err,
                   size_t errlen);

/** Checks q as sylva_qsm_read does (values, parents, cycles); 0 or a negative status
 *  with a message naming the cylinder. */
int sylva_qsm_check(const sylva_qsm *q, char *err, size_t errlen);

/** Writes q as TreeQSM's text export (17 columns with a header row) or as
 *  SimpleForest's CSV; 0 or a negative status. */
int sylva_qsm_write_text(const sylva_qsm *q, const char *path);
int sylva_qsm_write_csv(const sylva_qsm *q, const char *path);

/* ---- Internal: the steps the readers in server/import share (sylva__ names; not
 * for callers outside this library) ---- */

/** Writes the name of cylinder i of a model being read into buf (len bytes), as a
 *  message should give it: "cylinder 12", "row 13", "ID 11". ctx is the reader's. */
typedef void (*sylva__qsm_namer)(const void *ctx, size_t i, char *buf, size_t len);

/** sylva_qsm_check with each cylinder named by name(ctx, i) (NULL: "cylinder N",
 *  N from 1 as TreeQSM counts). The message is "NAME: what is wrong". */
int sylva__qsm_check_named(const sylva_qsm *q, sylva__qsm_namer name, const void *ctx, char *err,
                           size_t errlen);

/** Scales each axis of a checked q to unit length. An axis already of unit length
 *  to 1e-12 is left as it is, so that reading a model written by this library
 *  gives back the same bytes. */
void sylva__qsm_normalise(sylva_qsm *q);

/** Makes room for one more cylinder in q, whose array holds *cap; 0 or SYLVA_ENOMEM. */
int sylva__qsm_grow(sylva_qsm *q, size_t *cap);


/** The readers behind sylva_qsm_read, with its contract (messages start "PATH: "):
 *  TreeQSM .mat (qsm_mat.c), TreeQSM text and SimpleForest CSV (qsm_text.c). The
 *  CSV reader also takes the columns length, axisX, axisY and axisZ, which
 *  sylva_qsm_write_csv adds so that a model comes back exactly: when all four are
 *  present they give length and axis instead of start and end. */
int sylva__qsm_read_mat(const char *path, int model, sylva_qsm *q, char *err, size_t errlen);
int sylva__qsm_read_text(const char *path, int model, sylva_qsm *q, char *err, size_t errlen);
int sylva__qsm_read_csv(const char *path, int model, sylva_qsm *q, char *err, size_t errlen);

#endif
