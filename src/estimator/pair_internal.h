/* Private state of the ping-pair estimator. */
#ifndef SASNAV_PAIR_INTERNAL_H
#define SASNAV_PAIR_INTERNAL_H

#include <stddef.h>

#include "sasnav/error.h"
#include "sasnav/estimator.h"

#define PAIR_LEVELS 3

typedef struct {
    int k, i;
    sasnav_grid grid;
    size_t np, nd;
    sasnav_op *op_p, *op_q;
    sasnav_cfloat *rho_p, *rho_q, *psi_p, *psi_q, *tmp, *data_tmp, *cgls_work;
    double *mod_p, *mod_q, *blur_tmp;
    double rho_p_norm;
} pair_level;

struct sasnav_pair {
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    sasnav_pair_opts opts;
    sasnav_ping_pose local; /* EPCA geometry of both pings in their centroid frames */
    size_t nd;
    sasnav_cfloat *data_p, *data_q;
    sasnav_pose nominal;
    int ready;
    pair_level level[PAIR_LEVELS];
    long applications;
    int evaluations;
};

#endif
