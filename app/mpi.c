/* The processes of an MPI job (`mpirun -np N sasnav navigate|image ...`):
 * cli.h, "MPI". Built with Open MPI when CMake finds it (SASNAV_HAVE_MPI);
 * otherwise, and when the tool was not started by an MPI launcher, one
 * process of one rank and no MPI call at all. */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef SASNAV_HAVE_MPI
#include <mpi.h>
#endif

static int mpi_rank = 0, mpi_size = 1;
#ifdef SASNAV_HAVE_MPI
static int mpi_active = 0;
#endif

/* Started by an MPI launcher: Open MPI's mpirun, or a PMI / PMIx one
 * (MPICH's hydra, Slurm's srun). A plain start stays out of MPI
 * altogether (no singleton initialisation: faster, and quiet in
 * containers without a network). */
static int launched_by_mpi(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"};
    for (size_t i = 0; i < sizeof vars / sizeof vars[0]; i++)
        if (getenv(vars[i])) return 1;
    return 0;
}

int cli_mpi_init(int *argc, char ***argv)
{
#ifdef SASNAV_HAVE_MPI
    if (!launched_by_mpi()) return 0;
    int provided = 0;
    /* FUNNELED: MPI is called by the main thread only; OpenMP threads
     * compute in between. */
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        fprintf(stderr, "sasnav: MPI could not be initialised\n");
        return 1;
    }
    mpi_active = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &mpi_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &mpi_size);
    /* Results are printed by rank 0 alone. */
    if (mpi_rank != 0 && !freopen("/dev/null", "w", stdout)) return 1;
#else
    (void)argc;
    (void)argv;
    const char *n = launched_by_mpi() ? getenv("OMPI_COMM_WORLD_SIZE") : NULL;
    if (!n) n = getenv("PMI_SIZE");
    if (n && atoi(n) > 1) {
        fprintf(stderr, "sasnav: started by an MPI launcher with %d processes, but this build has no "
                        "MPI (configure it with Open MPI installed: libopenmpi-dev)\n", atoi(n));
        return 1;
    }
#endif
    return 0;
}

void cli_mpi_finalize(void)
{
#ifdef SASNAV_HAVE_MPI
    if (mpi_active) MPI_Finalize();
    mpi_active = 0;
#endif
}

int cli_mpi_rank(void) { return mpi_rank; }
int cli_mpi_size(void) { return mpi_size; }

int cli_mpi_any(int failed, int *rank0_failed)
{
    int f0 = failed != 0, any = failed != 0;
#ifdef SASNAV_HAVE_MPI
    if (mpi_active && mpi_size > 1) {
        int mine = failed != 0;
        MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        MPI_Bcast(&f0, 1, MPI_INT, 0, MPI_COMM_WORLD);
    }
#endif
    if (rank0_failed) *rank0_failed = f0;
    return any;
}

int cli_mpi_gather(const void *mine, size_t n, void **all, size_t *n_all)
{
    *all = NULL;
    *n_all = 0;
    if (mpi_size == 1) {
        void *copy = malloc(n > 0 ? n : 1);
        if (!copy) return 1;
        if (n) memcpy(copy, mine, n);
        *all = copy;
        *n_all = n;
        return 0;
    }
#ifdef SASNAV_HAVE_MPI
    /* Counts in bytes as int (MPI's counts): at most 2 GB per rank, far
     * beyond a part's pair records or image rows in practice; refused
     * above. */
    int bad = n > (size_t)0x7fffffff, any_bad = 0;
    MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (any_bad) return 1;
    int count = (int)n;
    int *counts = NULL, *displs = NULL;
    char *buf = NULL;
    int fail = 0;
    /* Rank 0's allocations are agreed on before each collective that uses
     * them (a failure is every rank's return, never a mismatched call). */
    if (mpi_rank == 0) {
        counts = malloc(sizeof(int) * (size_t)mpi_size);
        displs = malloc(sizeof(int) * (size_t)mpi_size);
        fail = !counts || !displs;
    }
    MPI_Bcast(&fail, 1, MPI_INT, 0, MPI_COMM_WORLD);
    size_t total = 0;
    if (!fail) {
        MPI_Gather(&count, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (mpi_rank == 0) {
            for (int r = 0; r < mpi_size; r++) {
                displs[r] = (int)total;
                total += (size_t)counts[r];
            }
            fail = total > (size_t)0x7fffffff || !(buf = malloc(total > 0 ? total : 1));
        }
        MPI_Bcast(&fail, 1, MPI_INT, 0, MPI_COMM_WORLD);
    }
    if (!fail) MPI_Gatherv(mine, count, MPI_BYTE, buf, counts, displs, MPI_BYTE, 0, MPI_COMM_WORLD);
    free(counts);
    free(displs);
    if (fail) {
        free(buf);
        return 1;
    }
    if (mpi_rank == 0) {
        *all = buf;
        *n_all = total;
    }
    return 0;
#else
    return 1;
#endif
}

/* Blocking point-to-point transfers of n bytes (n < 2 GB: one tile). */
void cli_mpi_send(int dest, const void *buf, size_t n)
{
#ifdef SASNAV_HAVE_MPI
    if (mpi_active) MPI_Send(buf, (int)n, MPI_BYTE, dest, 0, MPI_COMM_WORLD);
#else
    (void)dest;
    (void)buf;
    (void)n;
#endif
}

void cli_mpi_recv(int src, void *buf, size_t n)
{
#ifdef SASNAV_HAVE_MPI
    if (mpi_active) MPI_Recv(buf, (int)n, MPI_BYTE, src, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
#else
    (void)src;
    (void)buf;
    (void)n;
#endif
}

void cli_mpi_abort(int code)
{
#ifdef SASNAV_HAVE_MPI
    if (mpi_active) MPI_Abort(MPI_COMM_WORLD, code);
#endif
    exit(code);
}
