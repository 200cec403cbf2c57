/*
 * Check macros shared by the C tests of the ABI: each counts a check, prints the failing
 * condition (with the library's last error message for statuses) and lets the test go on.
 * A test program ends with `return failures == 0 ? 0 : 1;`.
 */
#ifndef NBHD_TEST_CHECK_H
#define NBHD_TEST_CHECK_H

#include <stdio.h>
#include <string.h>

#include "nbhd.h"

static int checks = 0;
static int failures = 0;

#define CHECK(cond)                                                                            \
    do {                                                                                       \
        checks++;                                                                              \
        if (!(cond)) {                                                                         \
            failures++;                                                                        \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);           \
        }                                                                                      \
    } while (0)

/* Checks the status of a call, printing the library's message if it is not the one expected. */
#define CHECK_STATUS(call, expected)                                                           \
    do {                                                                                       \
        nbhd_status st_ = (call);                                                              \
        checks++;                                                                              \
        if (st_ != (expected)) {                                                               \
            failures++;                                                                        \
            fprintf(stderr, "%s:%d: %s gave %d (%s; %s), expected %s\n", __FILE__, __LINE__,   \
                    #call, (int)st_, nbhd_status_string(st_), nbhd_last_error_message(),         \
                    #expected);                                                                \
        }                                                                                      \
    } while (0)

/* Checks that the last error message of this thread contains `needle`. */
#define CHECK_MESSAGE(needle)                                                                  \
    do {                                                                                       \
        const char *m_ = nbhd_last_error_message();                                            \
        checks++;                                                                              \
        if (m_ == NULL || strstr(m_, (needle)) == NULL) {                                      \
            failures++;                                                                        \
            fprintf(stderr, "%s:%d: last error \"%s\" lacks \"%s\"\n", __FILE__, __LINE__,     \
                    m_ ? m_ : "(NULL)", (needle));                                             \
        }                                                                                      \
    } while (0)

#endif
