/* Error codes and the per-thread last-error message. */
#include "sasnav/error.h"

#include <stdarg.h>
#include <stdio.h>

static _Thread_local char last_message[512];

const char *sasnav_strerror(int status)
{
    switch (status) {
    case SASNAV_OK: return "success";
    case SASNAV_ERR_ARG: return "invalid argument";
    case SASNAV_ERR_NOMEM: return "out of memory";
    case SASNAV_ERR_IO: return "input/output error";
    case SASNAV_ERR_FORMAT: return "invalid or corrupt data";
    case SASNAV_ERR_GEOMETRY: return "impossible geometry";
    case SASNAV_ERR_NO_OVERLAP: return "pings do not overlap";
    case SASNAV_ERR_NOT_CONVERGED: return "did not converge";
    case SASNAV_ERR_FFT: return "FFT planning failed";
    case SASNAV_ERR_CONFIG: return "invalid configuration";
    case SASNAV_ERR_UNSUPPORTED: return "unsupported";
    case SASNAV_ERR_INTERNAL: return "internal error";
    default: return "unknown error";
    }
}

const char *sasnav_last_error(void) { return last_message; }

void sasnav_clear_error(void) { last_message[0] = '\0'; }

int sasnav_set_error(int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(last_message, sizeof last_message, fmt, ap);
    va_end(ap);
    return status;
}

int sasnav_prefix_error(int status, const char *fmt, ...)
{
    char detail[sizeof last_message], prefix[sizeof last_message];
    snprintf(detail, sizeof detail, "%s", last_message);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    /* longer messages are cut at the buffer's size (the return value says by
     * how much; nothing to do about it) */
    if (snprintf(last_message, sizeof last_message, "%s: %s", prefix, detail) < 0)
        last_message[0] = '\0';
    return status;
}
