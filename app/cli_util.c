/* Argument parsing and error reporting shared by the subcommands. */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cli_fail(const char *command, int rc, const char *fmt, ...)
{
    fprintf(stderr, "sasnav %s: ", command);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    if (rc < 0) {
        const char *detail = sasnav_last_error();
        fprintf(stderr, ": %s", detail && detail[0] ? detail : sasnav_strerror(rc));
    }
    fputc('\n', stderr);
    return 1;
}

int cli_parse_double(const char *text, double *out)
{
    if (!text || !*text) return -1;
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (errno || end == text || *end != '\0' || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

int cli_parse_int(const char *text, long lo, long hi, long *out)
{
    if (!text || !*text) return -1;
    char *end = NULL;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno || end == text || *end != '\0' || v < lo || v > hi) return -1;
    *out = v;
    return 0;
}

int cli_parse_doubles(const char *text, int n, double *out)
{
    if (!text) return -1;
    char buf[512];
    if (strlen(text) >= sizeof buf) return -1;
    strcpy(buf, text);
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    int i = 0;
    for (; tok && i < n; i++, tok = strtok_r(NULL, ",", &save))
        if (cli_parse_double(tok, &out[i])) return -1;
    return (i == n && tok == NULL) ? 0 : -1;
}

int cli_parse_grid(const char *text, sasnav_grid *grid)
{
    double v[6];
    if (cli_parse_doubles(text, 6, v)) return -1;
    if (v[2] != floor(v[2]) || v[5] != floor(v[5]) || v[2] < 1 || v[5] < 1 || v[2] > 1e5 ||
        v[5] > 1e5)
        return -1;
    return sasnav_grid_make(v[0], v[1], (int)v[2], v[3], v[4], (int)v[5], grid) ? -1 : 0;
}
