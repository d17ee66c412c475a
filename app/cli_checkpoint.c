/* --checkpoint FILE: resuming interrupted navigations (cli.h). */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void record_progress(const sasnav_navigate_progress *pr, void *user)
{
    cli_checkpoint *c = user;
    if (pr->result && pr->resumed) c->n_resumed++;
    if (pr->result && !pr->resumed && !c->write_failed) {
        sasnav_pair_record r;
        memset(&r, 0, sizeof r);
        r.key = pr->key;
        r.p = pr->p;
        r.q = pr->q;
        r.status = pr->status;
        r.result = *pr->result;
        if (sasnav_checkpoint_append(c->ck, &r)) {
            /* The job goes on; only its resumability is lost. */
            c->write_failed = 1;
            fprintf(stderr, "sasnav %s: warning: %s; going on without checkpointing\n", c->command,
                    sasnav_last_error());
        } else {
            c->n_appended++;
        }
    }
    if (c->inner) c->inner(pr, c->inner_user);
}

int cli_checkpoint_begin(cli_checkpoint *c, const char *command, const char *path,
                         sasnav_navigate_opts *no)
{
    memset(c, 0, sizeof *c);
    c->command = command;
    c->path = path;
    if (!path) return 0;
    char job[64];
    snprintf(job, sizeof job, "sasnav %s", command);
    int rc = sasnav_checkpoint_open(path, job, &c->ck, &c->records, &c->n_records);
    if (rc) return cli_fail(command, rc, "cannot use checkpoint %s", path);
    if (c->n_records > 0)
        fprintf(stderr, "sasnav %s: resuming from %s (%d pairs estimated before)\n", command, path,
                c->n_records);
    c->inner = no->progress;
    c->inner_user = no->progress_user;
    no->progress = record_progress;
    no->progress_user = c;
    no->done = c->records;
    no->n_done = c->n_records;
    return 0;
}

void cli_checkpoint_end(cli_checkpoint *c, int success)
{
    if (!c->ck) return;
    if (c->n_records > 0)
        fprintf(stderr, "sasnav %s: %d pairs taken from checkpoint %s, %d estimated\n", c->command,
                c->n_resumed, c->path, c->n_appended);
    int rc = sasnav_checkpoint_close(c->ck, success);
    if (rc) fprintf(stderr, "sasnav %s: warning: %s\n", c->command, sasnav_last_error());
    else if (!success)
        fprintf(stderr, "sasnav %s: %d pairs kept in %s: run the same command again to resume\n",
                c->command, c->n_records + c->n_appended, c->path);
    c->ck = NULL;
    free(c->records);
    c->records = NULL;
}
