/* sasnav image: backprojection of a run with given navigation. */
#include "cli.h"
#include "sasnav/io.h"
#include "sasnav/plot.h"

#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *help =
    "usage: sasnav image run.h5 [--nav nav.h5 | --truth] [--grid X0,X1,NX,Y0,Y1,NY]\n"
    "                    [--png image.png] [--dynamic-range DB] [--threads N]\n"
    "                    [--ping P [--cgls K] [--tikhonov L]]\n"
    "                    [--ffbp [--ffbp-oversampling S]] -o image.h5\n"
    "\n"
    "Backprojects every ping of the run (sum of adjoint ping operators) on a\n"
    "grid and writes the complex image (docs/format.md) and optionally a PNG in dB.\n"
    "\n"
    "  --nav FILE        navigation to image with (default: the run's own /nav)\n"
    "  --truth           image with the run's ground-truth poses (simulations)\n"
    "  --grid ...        along-track x0,x1,nx and range y0,y1,ny (m); default: the\n"
    "                    track extent +-0.5 m by the range of interest +-0.8 m at\n"
    "                    quarter-element pixels\n"
    "  --png FILE        also write |image| in dB with axes and a colour bar\n"
    "  --dynamic-range DB  colour scale depth (default 40)\n"
    "  --threads N       OpenMP threads (default: all cores)\n"
    "  --ping P          image ping P alone (0-based)\n"
    "  --cgls K          with --ping: the regularised pseudo-inverse of the ping\n"
    "                    by K CGLS iterations instead of its backprojection\n"
    "  --tikhonov L      Tikhonov weight of the CGLS inverse (default 0)\n"
    "  --ffbp            fast factorised backprojection: subapertures on polar\n"
    "                    grids merged two by two (faster on long apertures; the\n"
    "                    error against direct backprojection: docs/survey.md)\n"
    "  --ffbp-oversampling S  polar grids' sampling over Nyquist (default 2;\n"
    "                    1.25..4: higher is more exact and slower)\n"

    "  -o FILE           output image file (HDF5)\n"
    "\n"
    "Any grid size: the backprojection runs in tiles of rows (about 180 MB of\n"
    "operator each), the run read ping by ping. 'mpirun -np N sasnav image ...'\n"
    "gives each process a band of rows; rank 0 writes the same image as one\n"
    "process, bit for bit (docs/survey.md).\n";

static int default_grid(const sasnav_run *run, const sasnav_ping_pose *nav, sasnav_grid *g)
{
    double xmin = INFINITY, xmax = -INFINITY;
    for (int p = 0; p < run->n_pings; p++) {
        sasnav_pose c = sasnav_ping_centroid(&nav[p]);
        if (c.x < xmin) xmin = c.x;
        if (c.x > xmax) xmax = c.x;
    }
    double res = run->sys.sound_speed / (4.0 * run->sys.bandwidth);
    double d_rx = sasnav_array_min_rx_length(&run->array);
    if (d_rx > 0 && d_rx / 4.0 < res) res = d_rx / 4.0;
    double r0 = run->range_of_interest > 0 ? run->range_of_interest : 10.0;
    xmin -= 0.5;
    xmax += 0.5;
    int nx = (int)ceil((xmax - xmin) / res) + 1, ny = (int)ceil(1.6 / res) + 1;
    return sasnav_grid_make(xmin, xmin + (nx - 1) * res, nx, r0 - 0.8, r0 - 0.8 + (ny - 1) * res, ny, g);
}

/* One ping: its backprojection, or its CGLS pseudo-inverse (k > 0). */
static int image_one_ping(const sasnav_run *run, const sasnav_ping_pose *pose, int p,
                          const sasnav_grid *grid, const sasnav_op_opts *oo, int k, double tikhonov,
                          sasnav_cfloat *image)
{
    size_t np = (size_t)grid->nx * grid->ny;
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    if (!x || !y) {
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    sasnav_grid_points(grid, (sasnav_pose){0, 0, 0}, x, y);
    sasnav_op *op = NULL;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)np, x, y, oo, &op);
    free(x);
    free(y);
    if (!rc) rc = sasnav_op_set_ping(op, pose, run->channel_offset);
    const sasnav_cfloat *data = NULL;
    sasnav_cfloat *buf = malloc(sizeof *buf * sasnav_run_ping_size(run));
    if (!rc) rc = buf ? sasnav_run_get_ping(run, p, buf, &data) : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    if (!rc && k > 0) {
        sasnav_cgls_opts co = {k, tikhonov};
        rc = sasnav_cgls(op, data, &co, image, NULL);
    } else if (!rc) {
        rc = sasnav_op_adjoint(op, data, image);
    }
    free(buf);
    sasnav_op_destroy(op);
    return rc;
}

/* Progress in (tile, ping) steps over the whole image: `base` steps of
 * earlier tiles, plus the tile being made. */
typedef struct {
    cli_progress *prog;
    long base, total;
} tile_progress;

static void tile_ping_progress(int done, int total, void *user)
{
    (void)total;
    tile_progress *tp = user;
    long d = tp->base + done;
    cli_progress_update(tp->prog, (int)(d < INT_MAX ? d : INT_MAX), (int)(tp->total < INT_MAX ? tp->total : INT_MAX));
}

/* Images larger than this are written but not drawn (--png). */
#define PNG_MAX_PIXELS 67108864.0

/* The backprojection in tiles (each rank of an MPI job makes the tiles t
 * with t % ranks == rank, in order; rank 0 writes every tile as it comes,
 * so no process holds more than a tile). Returns 0, or a CLI status after
 * a message. */
static int image_tiles(const char *output, const sasnav_run *run, const sasnav_ping_pose *nav,
                       const sasnav_grid *g, const sasnav_op_opts *oo, const sasnav_ffbp_opts *ffbp)
{
    int ranks = cli_mpi_size(), rank = cli_mpi_rank();
    int side = (int)floor(sqrt((double)(ffbp ? SASNAV_FFBP_TILE_PAIRS : SASNAV_BACKPROJECT_TILE_PAIRS) /
                               run->array.n_rx));
    if (side < 1) side = 1;
    int tw = g->nx < side ? g->nx : side, th = g->ny < side ? g->ny : side;
    int ntx = (g->nx + tw - 1) / tw;
    if (ranks > 1 && !ffbp) {
        /* At least four tiles per rank, for balance. (Not for FFBP, whose
         * values depend on the tiles: the same tiles as one process give
         * the same bits.) */
        int rows_wanted = (4 * ranks + ntx - 1) / ntx;
        int h = (g->ny + rows_wanted - 1) / rows_wanted;
        if (h < th) th = h > 0 ? h : 1;
    }
    int nty = (g->ny + th - 1) / th;
    long ntiles = (long)ntx * nty;
    sasnav_cfloat *buf = malloc(sizeof *buf * (size_t)tw * (size_t)th);
    sasnav_image_writer *w = NULL;
    int rc = buf ? SASNAV_OK : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a tile");
    if (!rc && rank == 0) rc = sasnav_image_writer_open(output, g, tw, th, &w);
    int rank0_failed;
    if (cli_mpi_any(rc != 0, &rank0_failed)) {
        free(buf);
        sasnav_image_writer_abort(w);
        return rc && (rank == 0 || !rank0_failed) ? cli_fail("image", rc, "cannot write %s", output) : CLI_FAILURE;
    }
    cli_progress prog;
    cli_progress_init(&prog, "image", "pings");
    tile_progress tp = {&prog, 0, ntiles * run->n_pings};
    for (long t = 0; t < ntiles; t++) {
        int owner = (int)(t % ranks);
        int c0 = (int)(t % ntx) * tw, r0 = (int)(t / ntx) * th;
        int c1 = c0 + tw < g->nx ? c0 + tw : g->nx, r1 = r0 + th < g->ny ? r0 + th : g->ny;
        size_t bytes = sizeof *buf * (size_t)(c1 - c0) * (size_t)(r1 - r0);
        if (owner == rank) {
            rc = ffbp ? sasnav_ffbp_tile(run, nav, g, c0, c1, r0, r1, oo, ffbp, buf, tile_ping_progress, &tp)
                      : sasnav_backproject_tile(run, nav, g, c0, c1, r0, r1, oo, buf, tile_ping_progress, &tp);
            if (rc) cli_fail("image", rc, "backprojection failed");
            if (rank != 0) {
                int st = rc;
                cli_mpi_send(0, &st, sizeof st);
                if (rc) break;
                cli_mpi_send(0, buf, bytes);
                continue;
            }
        } else if (rank == 0) {
            int st = 0;
            cli_mpi_recv(owner, &st, sizeof st);
            if (st) {
                rc = CLI_FAILURE;
                fprintf(stderr, "sasnav image: rank %d failed (above): %s not written\n", owner, output);
            } else {
                cli_mpi_recv(owner, buf, bytes);
            }
        } else {
            continue;
        }
        /* rank 0 */
        if (!rc) {
            rc = sasnav_image_writer_put(w, c0, c1, r0, r1, buf);
            if (rc) cli_fail("image", rc, "cannot write %s", output);
        }
        if (rc) break;
        tp.base += run->n_pings;
        tile_ping_progress(0, 0, &tp);
    }
    cli_progress_end(&prog);
    free(buf);
    if (rank != 0) return rc ? CLI_FAILURE : 0;
    if (rc) {
        sasnav_image_writer_abort(w);
        if (ranks > 1) cli_mpi_abort(CLI_FAILURE); /* the others may wait on a send */
        return CLI_FAILURE;
    }
    rc = sasnav_image_writer_finish(w);
    if (rc) return cli_fail("image", rc, "cannot write %s", output);
    return 0;
}

int cmd_image(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"nav", required_argument, 0, 'n'},  {"truth", no_argument, 0, 'T'},
        {"grid", required_argument, 0, 'g'}, {"png", required_argument, 0, 'P'},
        {"dynamic-range", required_argument, 0, 'd'}, {"threads", required_argument, 0, 't'},
        {"output", required_argument, 0, 'o'}, {"help", no_argument, 0, 'h'},
        {"ping", required_argument, 0, 'p'}, {"cgls", required_argument, 0, 'k'},
        {"tikhonov", required_argument, 0, 'L'}, {"ffbp", no_argument, 0, 'F'},
        {"ffbp-oversampling", required_argument, 0, 'O'},
        {0, 0, 0, 0}};
    int use_ffbp = 0;
    sasnav_ffbp_opts fo;
    sasnav_ffbp_default_opts(&fo);
    long ping = -1, cgls = 0;
    double tikhonov = 0;
    const char *navfile = NULL, *gridtext = NULL, *png = NULL, *output = NULL;
    int use_truth = 0;
    double dr = 40.0;
    long threads = 0;
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "n:Tg:P:d:t:o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'n': navfile = optarg; break;
        case 'T': use_truth = 1; break;
        case 'g': gridtext = optarg; break;
        case 'P': png = optarg; break;
        case 'd':
            if (cli_parse_double(optarg, &dr) || !(dr > 0))
                return cli_usage("image", "--dynamic-range needs a positive number of dB");
            break;
        case 't':
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("image", "--threads needs an integer 0..1024");
            break;
        case 'o': output = optarg; break;
        case 'p':
            if (cli_parse_int(optarg, 0, 10000000, &ping)) return cli_usage("image", "--ping needs a ping index");
            break;
        case 'k':
            if (cli_parse_int(optarg, 1, 10000, &cgls)) return cli_usage("image", "--cgls needs 1..10000 iterations");
            break;
        case 'L':
            if (cli_parse_double(optarg, &tikhonov) || tikhonov < 0)
                return cli_usage("image", "--tikhonov needs a number >= 0");
            break;
        case 'F': use_ffbp = 1; break;
        case 'O':
            if (cli_parse_double(optarg, &fo.oversampling) || !(fo.oversampling >= 1.25 && fo.oversampling <= 4))
                return cli_usage("image", "--ffbp-oversampling needs a number in 1.25..4");
            use_ffbp = 1;
            break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("image", argv, longopts);
        }
    }
    if (optind != argc - 1) return cli_usage("image", "exactly one input run file is required");
    if (cgls && ping < 0) return cli_usage("image", "--cgls needs --ping");
    if (use_ffbp && ping >= 0) return cli_usage("image", "--ffbp images whole runs, not --ping");
    if (!output) return cli_usage("image", "an output file is required (-o image.h5)");
    if (navfile && use_truth) return cli_usage("image", "--nav and --truth exclude each other");
    const char *input = argv[optind];
    sasnav_grid grid;
    if (gridtext && cli_parse_grid(gridtext, &grid))
        return cli_usage("image", "--grid: %s", sasnav_last_error());

    int ranks = cli_mpi_size(), rank = cli_mpi_rank(), rank0_failed = 0;
    if (ranks > 1 && ping >= 0)
        return cli_usage("image", "--ping images one ping in one process, not in the %d of mpirun", ranks);

    /* Streamed: the pings are read one at a time (per tile of the grid). */
    sasnav_run *run = NULL;
    int rc = sasnav_run_open(input, &run);
    if (cli_mpi_any(rc != 0, &rank0_failed)) {
        if (rc && (rank == 0 || !rank0_failed)) return cli_fail("image", rc, "cannot read %s", input);
        sasnav_run_free(run);
        return CLI_FAILURE;
    }
    sasnav_ping_pose *nav = run->nav, *own_nav = NULL;
    if (use_truth) {
        if (!run->truth) {
            sasnav_run_free(run);
            return cli_fail("image", 0, "%s holds no ground truth", input);
        }
        nav = run->truth;
    } else if (navfile) {
        int n = 0;
        rc = sasnav_nav_read(navfile, &n, &own_nav, NULL);
        if (rc) {
            sasnav_run_free(run);
            return cli_fail("image", rc, "cannot read navigation %s", navfile);
        }
        if (n != run->n_pings) {
            free(own_nav);
            int np = run->n_pings;
            sasnav_run_free(run);
            return cli_fail("image", 0, "%s has %d pings but %s has %d", navfile, n, input, np);
        }
        nav = own_nav;
    }
    if (!gridtext && (rc = default_grid(run, nav, &grid))) {
        free(own_nav);
        sasnav_run_free(run);
        return cli_fail("image", rc, "default grid");
    }
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = (int)threads;
    if (ping >= run->n_pings) {
        free(own_nav);
        int n = run->n_pings;
        sasnav_run_free(run);
        return cli_fail("image", 0, "--ping %ld: the run has %d pings", ping, n);
    }
    if (ping >= 0) {
        /* One ping, one process: the whole image in memory. */
        sasnav_cfloat *image = malloc(sizeof(sasnav_cfloat) * (size_t)grid.nx * (size_t)grid.ny);
        rc = image ? image_one_ping(run, &nav[ping], (int)ping, &grid, &oo, (int)cgls, tikhonov, image)
                   : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a %d x %d image", grid.ny, grid.nx);
        free(own_nav);
        sasnav_run_free(run);
        if (!rc) rc = sasnav_image_write(output, &grid, image);
        free(image);
        if (rc) return cli_fail("image", rc, "cannot make %s", output);
    } else {
        rc = image_tiles(output, run, nav, &grid, &oo, use_ffbp ? &fo : NULL);
        free(own_nav);
        sasnav_run_free(run);
        if (rc) return rc;
        if (rank != 0) return 0;
    }
    if (png) {
        char title[256];
        snprintf(title, sizeof title, "%s (%s navigation)", input,
                 use_truth ? "true" : navfile ? navfile : "nominal");
        if ((double)grid.nx * grid.ny > PNG_MAX_PIXELS)
            return cli_fail("image", 0, "%s is written; a %d x %d image is too large for --png (at most %.0f "
                                        "pixels: crop it with --grid)",
                            output, grid.ny, grid.nx, PNG_MAX_PIXELS);
        sasnav_grid g2;
        sasnav_cfloat *image = NULL;
        rc = sasnav_image_read(output, &g2, &image);
        if (!rc) rc = sasnav_plot_image_db(png, &g2, image, dr, title);
        free(image);
        if (rc) return cli_fail("image", rc, "cannot write %s", png);
    }
    fprintf(stderr, "sasnav image: %d x %d pixels -> %s%s%s\n", grid.ny, grid.nx, output,
            png ? ", " : "", png ? png : "");
    return 0;
}
