#pragma once
// The only assertion macros: for bugs, never for bad input (that is a Status).
#include <cstdio>
#include <cstdlib>

#define VOXPLAN_ASSERT(cond)                                                            \
  do {                                                                                  \
    if (!(cond)) {                                                                      \
      std::fprintf(stderr, "%s:%d: assertion failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                     \
    }                                                                                   \
  } while (0)

#ifdef NDEBUG
#define VOXPLAN_DASSERT(cond) ((void)0)
#else
#define VOXPLAN_DASSERT(cond) VOXPLAN_ASSERT(cond)
#endif
