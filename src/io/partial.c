/* Outputs in progress (io.h: sasnav_remove_partial_outputs; textfile.h).
 *
 * Every writer of the I/O layer writes to a temporary name next to its
 * target and renames it onto the target when complete. The temporary names
 * in use are kept here, in fixed slots, so that a signal handler can remove
 * them (unlink is async-signal-safe; nothing here allocates or locks). A
 * slot is claimed with an atomic compare-and-swap (several threads may
 * write files at once), filled, then published; the handler only reads
 * published slots. */
#include "io/textfile.h"
#include "sasnav/io.h"
#include "sasnav/error.h"

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <errno.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PARTIAL_SLOTS 64
#define PARTIAL_PATH 4200

enum { SLOT_FREE = 0, SLOT_FILLING = 1, SLOT_READY = 2 };

static _Atomic int slot_state[PARTIAL_SLOTS];
static char slot_path[PARTIAL_SLOTS][PARTIAL_PATH];

int sasnav_partial_add(const char *tmp_path)
{
    if (!tmp_path || strlen(tmp_path) >= PARTIAL_PATH) return -1;
    for (int i = 0; i < PARTIAL_SLOTS; i++) {
        int expect = SLOT_FREE;
        if (atomic_compare_exchange_strong(&slot_state[i], &expect, SLOT_FILLING)) {
            strcpy(slot_path[i], tmp_path);
            atomic_store(&slot_state[i], SLOT_READY);
            return i;
        }
    }
    return -1; /* more than 64 outputs at once: this one is not covered */
}

void sasnav_partial_remove(int slot)
{
    if (slot >= 0 && slot < PARTIAL_SLOTS) atomic_store(&slot_state[slot], SLOT_FREE);
}

void sasnav_remove_partial_outputs(void)
{
    for (int i = 0; i < PARTIAL_SLOTS; i++)
        if (atomic_load(&slot_state[i]) == SLOT_READY) unlink(slot_path[i]);
}

void sasnav_partial_hold(sigset_t *old)
{
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, old);
}

void sasnav_partial_release(const sigset_t *old) { pthread_sigmask(SIG_SETMASK, old, NULL); }

int sasnav_output_check(const char *path)
{
    if (!path || !*path) return sasnav_set_error(SASNAV_ERR_ARG, "empty output path");
    struct stat st;
    if (stat(path, &st) != 0) return SASNAV_OK; /* absent (or unreachable: the write says why) */
    if (S_ISREG(st.st_mode)) return SASNAV_OK;
    return sasnav_set_error(SASNAV_ERR_IO,
                            "%s exists and is not a regular file (%s): outputs are written to a temporary "
                            "file renamed onto the target, which would replace it; name a file",
                            path, S_ISDIR(st.st_mode) ? "a directory" : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device" : S_ISFIFO(st.st_mode) ? "a pipe" : "not a file");
}
