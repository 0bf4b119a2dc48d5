"""The benchmarks' C clock: ``seconds()``, the monotonic clock in seconds (POSIX.1b
``clock_gettime(CLOCK_MONOTONIC)``), one snippet for every timed C program.

It opens the program (it defines ``_POSIX_C_SOURCE`` before any header is included).

Example
-------
>>> source = SECONDS + "int main(void) { double start = seconds(); ... }"
"""

SECONDS = r"""#define _POSIX_C_SOURCE 199309L
#include <time.h>

static double seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}
"""
