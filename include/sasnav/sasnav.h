/* sasnav -- the whole public API in one include.
 *
 * Two libraries (docs/library.md): the numerical core, libsasnav_core
 * (geometry, signal, operators, imaging, estimator, trajectory, simulators;
 * no file or terminal access), and the I/O layer, libsasnav (HDF5 runs,
 * navigation and images, YAML configs, the tank and AirSAS recordings,
 * plots), which links the core. With CMake, `sasnav::sasnav` brings both;
 * `sasnav::core` the core alone. Headers of the I/O layer: io.h, config.h,
 * plot.h, and the readers and writers in tank.h and airsas.h.
 *
 * Threads: each header states its contract. In short: the core keeps no
 * global state but the per-thread error message and FFTW's planner (sasnav's
 * planning is serialised, op.h "FFTW"); distinct objects may be used from
 * distinct threads, runs shared read-only; OpenMP inside calls follows each
 * options' nthreads (0 = omp_get_max_threads()). The I/O layer is not
 * thread-safe (HDF5: io.h, PLplot: plot.h). */
#ifndef SASNAV_SASNAV_H
#define SASNAV_SASNAV_H

#include "sasnav/version.h"
#include "sasnav/error.h"

/* numerical core */
#include "sasnav/model.h"
#include "sasnav/geometry.h"
#include "sasnav/run.h"
#include "sasnav/op.h"
#include "sasnav/image.h"
#include "sasnav/scene.h"
#include "sasnav/sim.h"
#include "sasnav/ingest.h"
#include "sasnav/estimator.h"
#include "sasnav/dpca.h"
#include "sasnav/trajectory.h"
#include "sasnav/navigate.h"
#include "sasnav/virtual.h"
#include "sasnav/refine.h"
#include "sasnav/validate.h"
#include "sasnav/tank.h"
#include "sasnav/airsas.h"

/* I/O layer */
#include "sasnav/io.h"
#include "sasnav/checkpoint.h"
#include "sasnav/config.h"
#include "sasnav/plot.h"

#endif
