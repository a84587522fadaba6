/* sylva: status codes shared by every library (libuv style). */
#ifndef SYLVA_STATUS_H
#define SYLVA_STATUS_H

/* X(name, message): one list generates the enum, sylva_strerror() and sylva_err_name(). */
#define SYLVA_STATUS_MAP(X)                                                      \
  X(NOMEM, "out of memory")                                                      \
  X(INVAL, "invalid argument")                                                   \
  X(RANGE, "value out of range")                                                 \
  X(OUTSIDE, "position outside the world")                                       \
  X(BLOCKED, "position inside an obstacle")                                      \
  X(OCCUPIED, "voxel already occupied by another stem")                          \
  X(TOOBIG, "too large for memory")                                              \
  X(NOTFOUND, "no such object")                                                  \
  X(BADIMAGE, "not a sylva snapshot")                                            \
  X(VERSION, "snapshot format version not supported")                            \
  X(CHECKSUM, "snapshot checksum mismatch")                                      \
  X(TRUNCATED, "snapshot truncated")                                             \
  X(FINISHED, "the world has finished growing")

/** Status of a call: 0 on success, a negative SYLVA_E* code on failure. */
typedef enum sylva_status {
  SYLVA_OK = 0,
#define SYLVA__STATUS_ENUM(name, msg) SYLVA_E##name,
  SYLVA__STATUS_FIRST = -100,
  SYLVA_STATUS_MAP(SYLVA__STATUS_ENUM)
#undef SYLVA__STATUS_ENUM
} sylva_status;

/** Human-readable message for a status ("out of memory"). */
const char *sylva_strerror(int status);
/** Symbolic name of a status ("SYLVA_ENOMEM"). */
const char *sylva_err_name(int status);

#endif
