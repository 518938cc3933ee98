/* The C tests' check: counts the checks and the failures, and prints each failure with its
 * place; a test's main returns failures ? 1 : 0. */
#ifndef TOM_TESTS_C_CHECK_H
#define TOM_TESTS_C_CHECK_H

#include <stdio.h>

static int failures = 0, checks = 0;

#define CHECK(condition)                                                             \
    do {                                                                             \
        ++checks;                                                                    \
        if (!(condition)) {                                                          \
            ++failures;                                                              \
            fprintf(stderr, "%s:%d: FAILED: %s\n", __FILE__, __LINE__, #condition); \
        }                                                                            \
    } while (0)

#endif
