/* Signals of the sasnav tool: SIGINT, SIGTERM, SIGHUP and SIGPIPE (a
 * reader of its output that went away, `sasnav ... | head`) remove the
 * temporary files of the outputs being written (previous outputs stay as
 * they were) and end the process as the signal would (exit status 128 + N
 * in a shell); SIGXFSZ (a file-size limit) is ignored so that the write
 * fails with EFBIG and is reported as an error like a full disk. */
#include "cli.h"

#include "sasnav/io.h"

#include <signal.h>
#include <string.h>

static void on_signal(int sig)
{
    sasnav_remove_partial_outputs();
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = SIG_DFL;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, NULL);
    raise(sig);
}

void cli_install_signal_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; k++) {
        struct sigaction old;
        /* keep "ignored" when the parent asked for it (nohup, background jobs) */
        if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        sigaction(sigs[k], &sa, NULL);
    }
    signal(SIGXFSZ, SIG_IGN);
}
