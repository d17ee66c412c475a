/* sasnav -- error codes and messages.
 *
 * Every library function that can fail returns an int: SASNAV_OK (0) on
 * success, one of the negative codes below otherwise. The codes are never
 * renumbered. A human-readable message describing the most recent failure in
 * the calling thread is available from sasnav_last_error().
 *
 * Threads: the message is thread-local (_Thread_local in src/core/error.c),
 * so every function here is safe from any thread and sees only that
 * thread's failures. A failure on an OpenMP worker inside a library call
 * reaches the caller as the return code; its message only where the call
 * copies it back to the calling thread (sasnav_navigate does).
 */
#ifndef SASNAV_ERROR_H
#define SASNAV_ERROR_H

#ifdef __cplusplus
extern "C" {
#endif

enum sasnav_status {
    SASNAV_OK = 0,
    SASNAV_ERR_ARG = -1,          /* invalid argument (NULL, negative size, NaN...) */
    SASNAV_ERR_NOMEM = -2,        /* allocation failed */
    SASNAV_ERR_IO = -3,           /* file missing, unreadable or unwritable */
    SASNAV_ERR_FORMAT = -4,       /* file present but corrupt / wrong layout / wrong shape */
    SASNAV_ERR_GEOMETRY = -5,     /* impossible geometry (scene behind sensors, zero range...) */
    SASNAV_ERR_NO_OVERLAP = -6,   /* two pings share no observed scene */
    SASNAV_ERR_NOT_CONVERGED = -7,/* an optimiser or iteration did not converge */
    SASNAV_ERR_FFT = -8,          /* FFTW could not make a plan */
    SASNAV_ERR_CONFIG = -9,       /* configuration file invalid */
    SASNAV_ERR_UNSUPPORTED = -10, /* feature not available in this build */
    SASNAV_ERR_INTERNAL = -11     /* a bug: please report */
};

/* Short static description of a status code (never NULL). */
const char *sasnav_strerror(int status);

/* Detailed message of the last failure in this thread ("" if none).
 * The returned pointer stays valid until the next sasnav call in the thread. */
const char *sasnav_last_error(void);

/* Records a formatted message for sasnav_last_error() and returns `status`.
 * Used by the library and by front ends that wrap it. */
int sasnav_set_error(int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Prefixes the last-error message of this thread with a formatted context
 * ("<context>: <previous message>") and returns `status`; for callers that
 * add where a failure happened (a file, a ping) to what went wrong. */
int sasnav_prefix_error(int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Clears the last-error message of this thread. */
void sasnav_clear_error(void);

#ifdef __cplusplus
}
#endif
#endif
