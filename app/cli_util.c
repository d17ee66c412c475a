/* Argument parsing and error reporting shared by the subcommands. */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <limits.h>
#include <sys/stat.h>

int cli_fail(const char *command, int rc, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (cli_mpi_size() > 1 && cli_mpi_rank() != 0)
        fprintf(stderr, "sasnav %s (rank %d of %d): %s", command, cli_mpi_rank(), cli_mpi_size(), msg);
    else
        fprintf(stderr, "sasnav %s: %s", command, msg);
    if (rc < 0) {
        const char *detail = sasnav_last_error();
        if (!detail || !detail[0]) detail = sasnav_strerror(rc);
        /* "cannot read X" + "X: cannot open: ..." -> "cannot read X: cannot
         * open: ...": the library's messages start with the path they are
         * about, which the command's message has just named. */
        const char *last = strrchr(msg, ' ');
        last = last ? last + 1 : msg;
        size_t n = strlen(last);
        if (n > 0 && !strncmp(detail, last, n) && detail[n] == ':' && detail[n + 1] == ' ') detail += n + 2;
        fprintf(stderr, ": %s", detail);
    }
    fputc('\n', stderr);
    return 1;
}

int cli_usage(const char *command, const char *fmt, ...)
{
    /* Every rank of an MPI job parses the same command line: rank 0 says it. */
    if (cli_mpi_rank() != 0) return CLI_USAGE;
    fprintf(stderr, "sasnav %s: ", command);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (see 'sasnav %s --help')\n", command);
    return CLI_USAGE;
}

int cli_distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    if (n > 63 || m > 63) return 64;
    int d[64][64];
    for (size_t i = 0; i <= n; i++) d[i][0] = (int)i;
    for (size_t j = 0; j <= m; j++) d[0][j] = (int)j;
    for (size_t i = 1; i <= n; i++)
        for (size_t j = 1; j <= m; j++) {
            int c = a[i - 1] != b[j - 1];
            int v = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
            if (d[i - 1][j - 1] + c < v) v = d[i - 1][j - 1] + c;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < v)
                v = d[i - 2][j - 2] + 1;
            d[i][j] = v;
        }
    return d[n][m];
}

const char *cli_nearest(const char *word, const char *const *candidates, int n)
{
    const char *best = NULL;
    int best_d = 1 << 30;
    size_t len = strlen(word);
    int limit = (int)len / 3 > 2 ? (int)len / 3 : 2;
    for (int k = 0; k < n; k++) {
        int d = cli_distance(word, candidates[k]);
        if (len >= 2 && !strncmp(candidates[k], word, len)) d = 1; /* an abbreviation */
        if (d < best_d) {
            best_d = d;
            best = candidates[k];
        }
    }
    return best_d <= limit ? best : NULL;
}

int cli_bad_option(const char *command, char **argv, const struct option *longopts)
{
    const char *token = optind > 0 ? argv[optind - 1] : "";
    if (optopt && optopt != '?' && (token[0] != '-' || token[1] != '-')) {
        for (int k = 0; longopts[k].name; k++)
            if (longopts[k].val == optopt && longopts[k].has_arg == required_argument)
                return cli_usage(command, "option -%c needs a value", optopt);
        return cli_usage(command, "unknown option '-%c'", optopt);
    }
    char name[64];
    const char *body = token[0] == '-' && token[1] == '-' ? token + 2 : token;
    size_t len = strcspn(body, "=");
    if (len >= sizeof name) len = sizeof name - 1;
    memcpy(name, body, len);
    name[len] = '\0';
    const char *names[128];
    int n = 0;
    for (int k = 0; longopts[k].name && n < 128; k++) {
        if (!strcmp(longopts[k].name, name)) {
            if (longopts[k].has_arg == no_argument)
                return cli_usage(command, "option '--%s' takes no value", name);
            return cli_usage(command, "option '--%s' needs a value", name);
        }
        names[n++] = longopts[k].name;
    }
    const char *near = cli_nearest(name, names, n);
    if (near) return cli_usage(command, "unknown option '%s' (did you mean '--%s'?)", token, near);
    return cli_usage(command, "unknown option '%s'", token);
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

int cli_parse_nonneg_or_inf(const char *text, double *out)
{
    double v;
    if (text && !strcmp(text, "inf")) v = INFINITY;
    else if (cli_parse_double(text, &v) || !(v >= 0)) return -1;
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
    if (cli_parse_doubles(text, 6, v)) {
        sasnav_set_error(SASNAV_ERR_ARG, "needs six numbers X0,X1,NX,Y0,Y1,NY, got '%s'", text);
        return -1;
    }
    if (v[2] != floor(v[2]) || v[5] != floor(v[5]) || v[2] < 1 || v[5] < 1 || v[2] > 1e5 ||
        v[5] > 1e5) {
        sasnav_set_error(SASNAV_ERR_ARG, "NX and NY must be whole numbers in 1..100000, got %g and %g",
                         v[2], v[5]);
        return -1;
    }
    /* the grid's own reason otherwise (bounds, size) */
    return sasnav_grid_make(v[0], v[1], (int)v[2], v[3], v[4], (int)v[5], grid) ? -1 : 0;
}

/* "realpath(directory)/name" of a path whose file need not exist; 0 when
 * the directory cannot be resolved. */
static int canonical(const char *path, char *out, size_t size)
{
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    const char *name = slash ? slash + 1 : path;
    size_t n = slash ? (size_t)(slash - path) : 0;
    if (n >= sizeof dir) return 0;
    if (slash && n == 0) strcpy(dir, "/");
    else if (slash) {
        memcpy(dir, path, n);
        dir[n] = '\0';
    } else {
        strcpy(dir, ".");
    }
    char real[PATH_MAX];
    if (!realpath(dir, real)) return 0;
    return snprintf(out, size, "%s/%s", real, name) < (int)size;
}

int cli_same_file(const char *a, const char *b)
{
    if (!strcmp(a, b)) return 1;
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    char ca[PATH_MAX + 256], cb[PATH_MAX + 256];
    return canonical(a, ca, sizeof ca) && canonical(b, cb, sizeof cb) && !strcmp(ca, cb);
}
