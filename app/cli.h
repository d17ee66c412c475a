/* Shared helpers of the sasnav command-line tool. */
#ifndef SASNAV_CLI_H
#define SASNAV_CLI_H

#include "sasnav/checkpoint.h"
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/navigate.h"

#include <getopt.h>

/* Prints "sasnav COMMAND: message" (with the library's last error when rc is
 * a library code) and returns 1, for `return cli_fail(...)`. */
int cli_fail(const char *command, int rc, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Exit statuses of the tool: 0 success, 1 a runtime failure (missing or
 * corrupt input, a computation that failed, an output that could not be
 * written), 2 a usage error (unknown or malformed option, missing argument,
 * conflicting options). */
enum { CLI_OK = 0, CLI_FAILURE = 1, CLI_USAGE = 2 };

/* Prints "sasnav COMMAND: message" and a pointer to the command's help;
 * returns CLI_USAGE, for `return cli_usage(...)`. */
int cli_usage(const char *command, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Edit distance (insertions, deletions, substitutions, transpositions). */
int cli_distance(const char *a, const char *b);

/* The candidate nearest to `word` (edit distance <= max(2, |word| / 3), or
 * a candidate that `word` begins); NULL when none is near. */
const char *cli_nearest(const char *word, const char *const *candidates, int n);

/* The usage error for what getopt_long returned '?' or ':' on (call with
 * opterr = 0): an unknown option (with the nearest known one suggested) or
 * an option missing its argument. Returns CLI_USAGE. */
int cli_bad_option(const char *command, char **argv, const struct option *longopts);

/* 1 when the two paths name the same file: the same text, or an existing
 * file with the same device and inode. */
int cli_same_file(const char *a, const char *b);

/* Parses exactly n comma-separated finite doubles. Returns 0 on success. */
int cli_parse_doubles(const char *text, int n, double *out);
/* Parses a finite double / an int in [lo, hi]. Returns 0 on success. */
int cli_parse_double(const char *text, double *out);
int cli_parse_int(const char *text, long lo, long hi, long *out);
/* Parses a finite double >= 0, or "inf" (INFINITY). Returns 0 on success. */
int cli_parse_nonneg_or_inf(const char *text, double *out);
/* Parses X0,X1,NX,Y0,Y1,NY into a grid. */
int cli_parse_grid(const char *text, sasnav_grid *grid);

/* MPI (app/mpi.c). `mpirun -np N sasnav simulate|navigate|image ...` runs
 * N ranks of one job; the other commands refuse more than one. Only rank 0 writes
 * files and prints results (the other ranks' stdout goes to /dev/null).
 * Without MPI in the build, or when not started by an MPI launcher: rank
 * 0 of 1 and no MPI call.
 * cli_mpi_init: returns 0, or 1 after a message (MPI failed, or several
 * processes without MPI support). */
int cli_mpi_init(int *argc, char ***argv);
void cli_mpi_finalize(void);
int cli_mpi_rank(void);
int cli_mpi_size(void);
/* Collective: 1 when any rank passes failed != 0; *rank0_failed (may be
 * NULL) tells whether rank 0 did (it then reports the failure; a rank
 * reports its own only when rank 0 has nothing to say). */
int cli_mpi_any(int failed, int *rank0_failed);
/* Collective: the n bytes of every rank, concatenated in rank order, at
 * rank 0 (*all malloc'd, *n_all bytes; NULL elsewhere). Returns 0, or 1
 * on every rank when it could not be done (out of memory). */
int cli_mpi_gather(const void *mine, size_t n, void **all, size_t *n_all);
/* Blocking transfers of n bytes between two ranks (no-ops in one process). */
void cli_mpi_send(int dest, const void *buf, size_t n);
void cli_mpi_recv(int src, void *buf, size_t n);
/* Ends the whole job with `code` (every rank), after a failure that other
 * ranks may be waiting on. */
void cli_mpi_abort(int code);

/* SIGINT / SIGTERM / SIGHUP remove partial outputs, then end the process;
 * SIGXFSZ is ignored (app/signals.c). */
void cli_install_signal_handlers(void);

/* Progress of a long command: on a terminal a bar redrawn at every
 * update; otherwise a line on stderr at most every 10 s (the environment
 * variable SASNAV_PROGRESS_SECONDS sets the period; 0: every update) and
 * a last one at the end when any was printed. Count, rate and time left
 * (total 0: unknown, no time left). app/progress.c. */
typedef struct {
    const char *command, *unit;
    double t0, last, interval;
    int tty, lines, open_bar;
} cli_progress;
void cli_progress_init(cli_progress *p, const char *command, const char *unit);
void cli_progress_update(cli_progress *p, int done, int total);
/* Ends a bar's line (after the last update, before other output). */
void cli_progress_end(cli_progress *p);
/* sasnav_ping_progress_fn (image.h) over a cli_progress (user). */
void cli_ping_progress(int done, int total, void *user);

/* --checkpoint FILE of the pair-estimating commands (navigate, validate):
 * the records in FILE are given to the navigation as opts->done, every
 * pair estimated is appended, and FILE is removed once the output is
 * written (app/cli_checkpoint.c; checkpoint.h). */
typedef struct {
    sasnav_checkpoint *ck;
    sasnav_pair_record *records; /* read from FILE (n_records) */
    int n_records;
    int n_resumed, n_appended;   /* pairs taken from FILE / written to it */
    int write_failed;
    const char *command, *path;
    sasnav_progress_fn inner;    /* the wrapped progress callback */
    void *inner_user;
} cli_checkpoint;

/* Opens `path` (NULL: no checkpoint, nothing else done) for `command`;
 * wraps no->progress and sets no->done / no->n_done. Returns 0, or 1
 * after printing the error. */
int cli_checkpoint_begin(cli_checkpoint *c, const char *command, const char *path,
                         sasnav_navigate_opts *no);
/* After the job: with success (the output written), removes the file;
 * otherwise keeps it and says how to resume. Reports the resumed pairs. */
void cli_checkpoint_end(cli_checkpoint *c, int success);

int cmd_simulate(int argc, char **argv);
int cmd_image(int argc, char **argv);
int cmd_pair(int argc, char **argv);
int cmd_cuts(int argc, char **argv);
int cmd_ingest(int argc, char **argv);
int cmd_navigate(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_tank(int argc, char **argv);
int cmd_validate(int argc, char **argv);
int cmd_refine(int argc, char **argv);
int cmd_ingest_wav(const char *dir, int decimation, double range, const char *output);

#endif
