/* Internal invariants, checked in debug builds. SYLVA_ASSERT(cond) aborts with the
 * condition and its place when cond is false; with NDEBUG it compiles to nothing
 * and cond is not evaluated. core/meson.build defines NDEBUG for the library in
 * builds without debug info (release), so the checks cost nothing there.
 *
 * Invariants are the library's own promises (a parent's slot below its child's,
 * live counts, scratch sizes). A caller's bad argument is not one: public functions
 * answer it with a negative sylva_status in every build. */
#ifndef SYLVA_DEBUG_H
#define SYLVA_DEBUG_H

/** Prints "sylva: FILE:LINE: FUNC: assertion failed: EXPR" and aborts. */
_Noreturn void sylva__assert_fail(const char *expr, const char *file, int line, const char *func);

#ifdef NDEBUG
#define SYLVA_ASSERT(cond) ((void)0)
#else
#define SYLVA_ASSERT(cond) \
  ((cond) ? (void)0 : sylva__assert_fail(#cond, __FILE__, __LINE__, __func__))
#endif

#endif
