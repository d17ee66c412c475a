"""ctypes mirrors of the C structs of include/sasnav/*.h and the prototypes of
the functions the binding calls.

Every Structure below copies its header's declaration field by field, in
order (enums are C ints). ``_c_name_`` is the C type name: the layout test
(tests/test_layout.py) compiles a program against include/ that prints
sizeof and offsetof of every field of every class listed in STRUCTS and
compares them with ctypes. Change a header, change this file.
"""

import ctypes
from ctypes import (
    CFUNCTYPE,
    POINTER,
    Structure,
    c_char,
    c_char_p,
    c_double,
    c_float,
    c_int,
    c_long,
    c_uint64,
    c_void_p,
)

# geometry.h, sim.h, estimator.h
MAX_RX = 128
MAX_TARGETS = 64
PAIR_SCAN_CANDIDATES = 4
PAIR_MAX_CANDIDATES = 8

# Pointers to sasnav_cfloat (float _Complex: two floats, re and im) are
# passed as addresses (c_void_p) of numpy complex64 buffers.
cfloat_p = c_void_p


class Pose(Structure):  # geometry.h
    _c_name_ = "sasnav_pose"
    _fields_ = [("x", c_double), ("y", c_double), ("theta", c_double)]


class PingPose(Structure):  # geometry.h
    _c_name_ = "sasnav_ping_pose"
    _fields_ = [("tx", Pose), ("array", Pose)]


class ChannelSizeC(Structure):  # geometry.h: sasnav_channel_size
    _c_name_ = "sasnav_channel_size"
    _fields_ = [
        ("rx_length", c_double),
        ("tx_length", c_double),
        ("rx_height", c_double),
        ("tx_height", c_double),
    ]


class SensorArrayC(Structure):  # geometry.h: sasnav_array
    _c_name_ = "sasnav_array"
    _fields_ = [
        ("n_rx", c_int),
        ("rx_u", c_double * MAX_RX),
        ("rx_length", c_double),
        ("tx_length", c_double),
        ("rx_height", c_double),
        ("tx_height", c_double),
        ("per_channel", c_int),
        ("size", ChannelSizeC * MAX_RX),
    ]


class SystemC(Structure):  # model.h: sasnav_system
    _c_name_ = "sasnav_system"
    _fields_ = [
        ("sound_speed", c_double),
        ("f0", c_double),
        ("bandwidth", c_double),
        ("sample_rate", c_double),
        ("taper", c_int),  # sasnav_taper
        ("attenuation", c_int),  # sasnav_attenuation
        ("beam_pattern", c_int),
    ]


class Window(Structure):  # model.h
    _c_name_ = "sasnav_window"
    _fields_ = [("t0", c_double), ("n_samples", c_int)]


class AidingC(Structure):  # run.h
    _c_name_ = "sasnav_aiding"
    _fields_ = [
        ("time", POINTER(c_double)),
        ("yaw_rate", POINTER(c_double)),
        ("yaw_rate_sigma", POINTER(c_double)),
        ("velocity", POINTER(c_double)),
        ("velocity_sigma", POINTER(c_double)),
    ]


class PingSourceC(Structure):  # run.h: a streamed run's reader (zero for runs in memory)
    _c_name_ = "sasnav_ping_source"
    _fields_ = [
        ("read", c_void_p),
        ("close", c_void_p),
        ("ctx", c_void_p),
    ]


class RunC(Structure):  # run.h
    _c_name_ = "sasnav_run"
    _fields_ = [
        ("sys", SystemC),
        ("array", SensorArrayC),
        ("win", Window),
        ("n_pings", c_int),
        ("raw", cfloat_p),
        ("nav", POINTER(PingPose)),
        ("truth", POINTER(PingPose)),
        ("ping_spacing", c_double),
        ("speed", c_double),
        ("tx_lag", c_double),
        ("range_of_interest", c_double),
        ("aiding", POINTER(AidingC)),
        ("source", PingSourceC),
        ("channel_offset", POINTER(PingPose)),
    ]


class GridC(Structure):  # image.h
    _c_name_ = "sasnav_grid"
    _fields_ = [
        ("x0", c_double),
        ("y0", c_double),
        ("dx", c_double),
        ("dy", c_double),
        ("nx", c_int),
        ("ny", c_int),
    ]


class FfbpOpts(Structure):  # image.h
    _c_name_ = "sasnav_ffbp_opts"
    _fields_ = [("oversampling", c_double)]


class OpOpts(Structure):  # op.h
    _c_name_ = "sasnav_op_opts"
    _fields_ = [
        ("tolerance", c_double),
        ("oversampling", c_double),
        ("pad_samples", c_int),
        ("nthreads", c_int),
    ]


class CglsOpts(Structure):  # image.h
    _c_name_ = "sasnav_cgls_opts"
    _fields_ = [("iterations", c_int), ("tikhonov", c_double)]


class SceneC(Structure):  # scene.h
    _c_name_ = "sasnav_scene"
    _fields_ = [
        ("n", c_int),
        ("x", POINTER(c_double)),
        ("y", POINTER(c_double)),
        ("amp", cfloat_p),
    ]


class RippleParams(Structure):  # scene.h
    _c_name_ = "sasnav_ripple_params"
    _fields_ = [
        ("x_min", c_double),
        ("x_max", c_double),
        ("y_min", c_double),
        ("y_max", c_double),
        ("density", c_double),
        ("ripple_period", c_double),
        ("ripple_angle", c_double),
        ("ripple_depth", c_double),
        ("background", c_double),
        ("disc_x", c_double),
        ("disc_y", c_double),
        ("disc_radius", c_double),
        ("disc_amplitude", c_double),
        ("seed", c_uint64),
    ]


class TrajectoryParams(Structure):  # sim.h
    _c_name_ = "sasnav_trajectory_params"
    _fields_ = [
        ("n_pings", c_int),
        ("ping_spacing", c_double),
        ("speed", c_double),
        ("x_start", c_double),
        ("surge_rms", c_double),
        ("sway_rms", c_double),
        ("yaw_rms", c_double),
        ("smooth_length", c_double),
        ("has_pair_error", c_int),
        ("pair_q", c_int),
        ("pair_error", Pose),
        ("tx_lag", c_double),
        ("circle_radius", c_double),
        ("true_bistatic", c_int),
        ("seed", c_uint64),
    ]


class AidingParams(Structure):  # sim.h
    _c_name_ = "sasnav_aiding_params"
    _fields_ = [
        ("enabled", c_int),
        ("gyro", c_int),
        ("dvl", c_int),
        ("gyro_arw", c_double),
        ("gyro_bias", c_double),
        ("dvl_noise", c_double),
        ("dvl_bias", c_double),
        ("dvl_scale", c_double),
        ("seed", c_uint64),
    ]


class ScenarioC(Structure):  # sim.h
    _c_name_ = "sasnav_scenario"
    _fields_ = [
        ("name", c_char * 64),
        ("sys", SystemC),
        ("array", SensorArrayC),
        ("range_min", c_double),
        ("range_max", c_double),
        ("range_of_interest", c_double),
        ("traj", TrajectoryParams),
        ("scene_kind", c_int),  # sasnav_scene_kind
        ("ripples", RippleParams),
        ("n_targets", c_int),
        ("target_x", c_double * MAX_TARGETS),
        ("target_y", c_double * MAX_TARGETS),
        ("target_amp", c_double * MAX_TARGETS),
        ("scene_file", c_char * 512),
        ("snr_db", c_double),
        ("noise_seed", c_uint64),
        ("aiding", AidingParams),
        ("image_grid", GridC),
        ("n_channel_tx", c_int),
        ("channel_tx_u", c_double * MAX_RX),
    ]


class PairOpts(Structure):  # estimator.h
    _c_name_ = "sasnav_pair_opts"
    _fields_ = [
        ("k", c_int),
        ("i", c_int),
        ("coarse_k", c_int),
        ("coarse_i", c_int),
        ("tikhonov", c_double),
        ("norm", c_int),  # sasnav_norm
        ("tx_lag", c_double),
        ("range", c_double),
        ("range_extent", c_double),
        ("cross_extent", c_double),
        ("pixel", c_double),
        ("coarse_pixel", c_double),
        ("search_grid", c_int),  # sasnav_search_grid
        ("blur", c_double),
        ("blur_cross", c_double),
        ("prior", Pose),
        ("box", Pose),
        ("yaw_sigma", c_double),
        ("surge_sigma", c_double),
        ("fix_yaw", c_int),
        ("grid_step", Pose),
        ("global_stage", c_int),
        ("error_extent", c_double),
        ("error_taper", c_double),
        ("min_overlap", c_double),
        ("max_evaluations", c_int),
        ("verdict_eta_max", c_double),
        ("verdict_margin_min", c_double),
        ("verdict_coincidence", c_double),
        ("verdict_margin_compact", c_double),
        ("nthreads", c_int),
        ("op", OpOpts),
        ("gpu", c_int),
        ("final_criterion", c_int),  # sasnav_final_criterion
        ("joint_k", c_int),
        ("joint_mu", c_double),
        ("joint_shift_max", c_double),
        ("joint_contrast_max", c_double),
        ("joint_eta_ratio", c_double),
        ("verdict_contrast", c_double),
        ("joint_coverage_min", c_double),
        ("equalise", c_double),
    ]


class PairCandidate(Structure):  # estimator.h
    _c_name_ = "sasnav_pair_candidate"
    _fields_ = [
        ("error", Pose),
        ("zeta_scan", c_double),
        ("zeta", c_double),
        ("eta", c_double),
        ("refined", c_int),
        ("same_as", c_int),
    ]


class PairResult(Structure):  # estimator.h
    _c_name_ = "sasnav_pair_result"
    _fields_ = [
        ("status", c_int),
        ("error", Pose),
        ("displacement", Pose),
        ("global_stage", Pose),
        ("zeta_stage", Pose),
        ("zeta", c_double),
        ("eta", c_double),
        ("overlap", c_double),
        ("ambiguity", c_double),
        ("evaluations", c_int),
        ("evaluations_global", c_int),
        ("evaluations_zeta", c_int),
        ("evaluations_eta", c_int),
        ("applications", c_long),
        ("seconds", c_double),
        ("seconds_global", c_double),
        ("seconds_zeta", c_double),
        ("seconds_eta", c_double),
        ("seconds_final", c_double),
        ("applications_global", c_long),
        ("applications_zeta", c_long),
        ("applications_eta", c_long),
        ("applications_final", c_long),
        ("evaluations_final", c_int),
        ("verdict", c_int),
        ("n_candidates", c_int),
        ("candidates", PairCandidate * PAIR_MAX_CANDIDATES),
        ("chosen", c_int),
        ("margin", c_double),
        ("final_criterion", c_int),  # sasnav_final_criterion
        ("joint_rejected", c_int),
        ("search_grid", c_int),  # sasnav_search_grid
        ("coincidence", c_int),
        ("contrast", c_double),
        ("contrast_q", c_double),
        ("equalised", c_int),
        ("equalise_peak", c_float),
    ]


class DpcaOpts(Structure):  # dpca.h
    _c_name_ = "sasnav_dpca_opts"
    _fields_ = [
        ("range", c_double),
        ("half_width", c_double),
        ("upsampling", c_int),
        ("max_sway", c_double),
        ("use_phase", c_int),
        ("unwrap", c_int),
        ("bistatic_correction", c_int),
        ("min_coherence", c_double),
        ("nthreads", c_int),
    ]


class NavigateProgress(Structure):  # navigate.h
    _c_name_ = "sasnav_navigate_progress"
    _fields_ = [
        ("done", c_int),
        ("total", c_int),
        ("p", c_int),
        ("q", c_int),
        ("status", c_int),
        ("result", POINTER(PairResult)),
        ("seconds", c_double),
        ("key", c_uint64),
        ("resumed", c_int),
    ]


class PairRecord(Structure):  # navigate.h
    _c_name_ = "sasnav_pair_record"
    _fields_ = [
        ("key", c_uint64),
        ("p", c_int),
        ("q", c_int),
        ("status", c_int),
        ("result", PairResult),
    ]


PROGRESS_FN = CFUNCTYPE(None, POINTER(NavigateProgress), c_void_p)


class NavigateOpts(Structure):  # navigate.h
    _c_name_ = "sasnav_navigate_opts"
    _fields_ = [
        ("method", c_int),  # sasnav_method
        ("long_baselines", c_int),
        ("pair", PairOpts),
        ("dpca", DpcaOpts),
        ("link_sigma", Pose),
        ("long_sigma", Pose),
        ("link_eta", c_double),
        ("align", c_int),
        ("resolve", c_int),
        ("use_aiding", c_int),
        ("motion_sigma", Pose),
        ("eta_weight", c_double),
        ("aiding_gate", c_double),
        ("eta_outlier", c_double),
        ("nthreads", c_int),
        ("speed_lags", c_int),
        ("aiding_bias_sigma", Pose),
        ("tx_yaw", c_int),
        ("reuse", c_void_p),  # const sasnav_navigation *
        ("done", POINTER(PairRecord)),
        ("n_done", c_int),
        ("compact_pairs", c_int),
        ("progress", PROGRESS_FN),
        ("progress_user", c_void_p),
    ]


class NavigatePair(Structure):  # navigate.h
    _c_name_ = "sasnav_navigate_pair"
    _fields_ = [
        ("p", c_int),
        ("q", c_int),
        ("status", c_int),
        ("nominal", Pose),
        ("result", PairResult),
        ("truth", Pose),
        ("error", Pose),
        ("verdict", c_int),
        ("first_verdict", c_int),
        ("resolution", c_int),
        ("aiding", Pose),
        ("aiding_sigma", Pose),
        ("fused", Pose),
        ("first_result", PairResult),
        ("first_status", c_int),
        ("eta_outlier", c_int),
    ]


class NavigationC(Structure):  # navigate.h: struct sasnav_navigation
    _c_name_ = "sasnav_navigation"
    _fields_ = [
        ("method", c_int),
        ("n_pings", c_int),
        ("n_pairs", c_int),
        ("pairs", POINTER(NavigatePair)),
        ("n_failed", c_int),
        ("n_flagged", c_int),
        ("n_resolved", c_int),
        ("aiding_used", c_int),
        ("n_skipped", c_int),
        ("centroids", POINTER(Pose)),
        ("nav", POINTER(PingPose)),
        ("track_angle", c_double),
        ("lsq_iterations", c_int),
        ("has_truth", c_int),
        ("truth_centroids", POINTER(Pose)),
        ("anchored", POINTER(PingPose)),
        ("cumulative", POINTER(Pose)),
        ("differential", POINTER(Pose)),
        ("rms_cumulative", Pose),
        ("rms_differential", Pose),
        ("seconds", c_double),
        ("seconds_pairs", c_double),
        ("seconds_per_pair", c_double),
        ("seconds_estimation", c_double),
        ("pairs_per_second", c_double),
        ("threads_over_pairs", c_int),
        ("packed", c_void_p),
        ("gyro_tx_yaw", c_int),
        ("pairs_tx_yaw", c_int),
        ("eta_median", c_double),
        ("n_eta_outliers", c_int),
        ("formal_sigma", POINTER(Pose)),
    ]


class VirtualOpts(Structure):  # virtual.h
    _c_name_ = "sasnav_virtual_opts"
    _fields_ = [
        ("k", c_int),
        ("interleave", c_int),
        ("stride", c_int),
        ("pair", PairOpts),
        ("closed", c_int),
        ("iterations", c_int),
        ("nthreads", c_int),
        ("keep_length", c_int),
        ("align_heading", c_int),
        ("along_input", c_int),
    ]


class VirtualPair(Structure):  # virtual.h
    _c_name_ = "sasnav_virtual_pair"
    _fields_ = [
        ("first_p", c_int),
        ("first_q", c_int),
        ("nominal", Pose),
        ("truth", Pose),
        ("est", PairResult),
        ("used", c_int),
        ("step", Pose),
    ]


class VirtualNavigationC(Structure):  # virtual.h: sasnav_virtual_navigation
    _c_name_ = "sasnav_virtual_navigation"
    _fields_ = [
        ("n_pings", c_int),
        ("k", c_int),
        ("stride", c_int),
        ("interleave", c_int),
        ("n_groups", c_int),
        ("n_pairs", c_int),
        ("closed", c_int),
        ("align_heading", c_int),
        ("along_input", c_int),
        ("misclosure", Pose),
        ("pairs", POINTER(VirtualPair)),
        ("centroid_in", POINTER(Pose)),
        ("centroid", POINTER(Pose)),
        ("layout_turn", POINTER(c_double)),
        ("turn_mean", c_double),
        ("turn_rms", c_double),
        ("turn_exposure", c_double),
        ("nav", POINTER(PingPose)),
        ("n_fallback", c_int),
        ("length_scale", c_double),
        ("iterations", c_int),
        ("seconds", c_double),
    ]


# Every mirrored struct (checked by tests/test_layout.py).
STRUCTS = [
    Pose, PingPose, ChannelSizeC, SensorArrayC, SystemC, Window, AidingC, PingSourceC, RunC, GridC, OpOpts, FfbpOpts,
    CglsOpts, SceneC, RippleParams, TrajectoryParams, AidingParams, ScenarioC,
    PairOpts, PairCandidate, PairResult, DpcaOpts, NavigateProgress,
    NavigateOpts, NavigatePair, NavigationC, VirtualOpts, VirtualPair, VirtualNavigationC,
]

# Constants and enum values of the headers the binding relies on (checked by
# tests/test_layout.py against the C compiler's view of them).
CONSTANTS = {
    "SASNAV_MAX_RX": MAX_RX,
    "SASNAV_MAX_TARGETS": MAX_TARGETS,
    "SASNAV_PAIR_SCAN_CANDIDATES": PAIR_SCAN_CANDIDATES,
    "SASNAV_PAIR_MAX_CANDIDATES": PAIR_MAX_CANDIDATES,
    "SASNAV_OK": 0,
    "SASNAV_ERR_ARG": -1,
    "SASNAV_ERR_IO": -3,
    "SASNAV_ERR_FORMAT": -4,
    "SASNAV_SCENE_FILE": 2,
    "SASNAV_NORM_MAX": 0,
    "SASNAV_NORM_P": 1,
    "SASNAV_NORM_Q": 2,
    "SASNAV_NORM_NONE": 3,
    "SASNAV_METHOD_SUBSPACE": 0,
    "SASNAV_METHOD_DPCA": 1,
    "SASNAV_METHOD_AIDING": 2,
    "SASNAV_VERDICT_OK": 0,
    "SASNAV_VERDICT_AMBIGUOUS": 1,
    "SASNAV_VERDICT_FAILED": 2,
    "SASNAV_VERDICT_NO_OVERLAP": 3,
    "SASNAV_VERDICT_UNCHECKED": 4,
}

# Headers the layout test includes (all but sasnav.h, which needs the
# generated version.h).
HEADERS = [
    "error.h", "model.h", "geometry.h", "run.h", "op.h", "image.h", "scene.h",
    "sim.h", "estimator.h", "dpca.h", "navigate.h", "io.h", "config.h", "virtual.h",
]

_i, _d, _v = c_int, c_double, None
_P = POINTER

# name: (restype, argtypes). Only public sasnav_ functions of include/sasnav
# (tests/test_layout.py checks that each is declared there).
PROTOTYPES = {
    # error.h, version.h
    "sasnav_last_error": (c_char_p, []),
    "sasnav_strerror": (c_char_p, [_i]),
    "sasnav_clear_error": (_v, []),
    "sasnav_version": (c_char_p, []),
    "sasnav_version_number": (_i, []),
    # model.h, geometry.h
    "sasnav_system_default": (_v, [_P(SystemC)]),
    "sasnav_system_check": (_i, [_P(SystemC)]),
    "sasnav_array_uniform": (_i, [_P(SensorArrayC), _i, _d, _d, _d]),
    "sasnav_array_check": (_i, [_P(SensorArrayC)]),
    "sasnav_array_set_sizes": (_i, [_P(SensorArrayC), _P(ChannelSizeC)]),
    "sasnav_ping_displacement": (Pose, [_P(PingPose), _P(PingPose)]),
    "sasnav_ping_centroid": (Pose, [_P(PingPose)]),
    "sasnav_wrap_angle": (_d, [_d]),
    # run.h
    "sasnav_run_alloc": (_i, [_P(SystemC), _P(SensorArrayC), _P(Window), _i, _i, _P(_P(RunC))]),
    "sasnav_run_set_channel_offset": (_i, [_P(RunC), _P(PingPose)]),
    "sasnav_run_alloc_aiding": (_i, [_P(RunC), _i, _i]),
    "sasnav_run_check": (_i, [_P(RunC)]),
    "sasnav_run_ping": (cfloat_p, [_P(RunC), _i]),
    "sasnav_run_subset": (_i, [_P(RunC), _P(_i), _i, _P(_i), _i, _P(_P(RunC))]),
    "sasnav_run_free": (_v, [_P(RunC)]),
    "sasnav_run_get_ping": (_i, [_P(RunC), _i, cfloat_p, _P(cfloat_p)]),
    "sasnav_run_ping_size": (ctypes.c_size_t, [_P(RunC)]),
    # io.h, config.h
    "sasnav_run_read": (_i, [c_char_p, _P(_P(RunC))]),
    "sasnav_run_open": (_i, [c_char_p, _P(_P(RunC))]),
    "sasnav_run_write": (_i, [c_char_p, _P(RunC)]),
    "sasnav_nav_read": (_i, [c_char_p, _P(_i), _P(_P(PingPose)), _P(_P(PingPose))]),
    "sasnav_nav_write": (_i, [c_char_p, _i, _P(PingPose), _P(PingPose)]),
    "sasnav_nav_write_sigma": (_i, [c_char_p, _i, _P(PingPose), _P(PingPose), _P(Pose)]),
    "sasnav_nav_read_sigma": (_i, [c_char_p, _P(_i), _P(_P(Pose))]),
    "sasnav_image_read": (_i, [c_char_p, _P(GridC), _P(cfloat_p)]),
    "sasnav_image_write": (_i, [c_char_p, _P(GridC), cfloat_p]),
    "sasnav_config_load": (_i, [c_char_p, _P(ScenarioC)]),
    "sasnav_config_write": (_i, [c_char_p, _P(ScenarioC)]),
    # image.h, op.h
    "sasnav_grid_make": (_i, [_d, _d, _i, _d, _d, _i, _P(GridC)]),
    "sasnav_grid_check": (_i, [_P(GridC)]),
    "sasnav_grid_points": (_v, [_P(GridC), Pose, _P(_d), _P(_d)]),
    "sasnav_backproject": (_i, [_P(RunC), _P(PingPose), _P(GridC), _P(OpOpts), cfloat_p]),
    "sasnav_ffbp_tile": (_i, [_P(RunC), _P(PingPose), _P(GridC), c_int, c_int, c_int, c_int, _P(OpOpts),
                              _P(FfbpOpts), cfloat_p, c_void_p, c_void_p]),
    "sasnav_op_default_opts": (_v, [_P(OpOpts)]),
    "sasnav_op_create": (_i, [_P(SystemC), _P(SensorArrayC), _P(Window), _i, _P(_d), _P(_d),
                              _P(OpOpts), _P(c_void_p)]),
    "sasnav_op_set_geometry": (_i, [c_void_p, _P(PingPose)]),
    "sasnav_op_set_ping": (_i, [c_void_p, _P(PingPose), _P(PingPose)]),
    "sasnav_op_adjoint": (_i, [c_void_p, cfloat_p, cfloat_p]),
    "sasnav_op_destroy": (_v, [c_void_p]),
    "sasnav_cgls": (_i, [c_void_p, cfloat_p, _P(CglsOpts), cfloat_p, cfloat_p]),
    # scene.h, sim.h
    "sasnav_scene_from_image": (_i, [_d, _d, _d, _d, _i, _i, cfloat_p, _d, c_uint64,
                                     _P(_P(SceneC))]),
    "sasnav_scene_free": (_v, [_P(SceneC)]),
    "sasnav_scenario_preset": (_i, [c_char_p, _P(ScenarioC)]),
    "sasnav_scenario_seed": (_v, [_P(ScenarioC), c_uint64]),
    "sasnav_scenario_check": (_i, [_P(ScenarioC)]),
    "sasnav_simulate": (_i, [_P(ScenarioC), _P(SceneC), _P(OpOpts), _P(_P(RunC))]),
    # estimator.h
    "sasnav_pair_default_opts": (_v, [_P(PairOpts)]),
    "sasnav_verdict_name": (c_char_p, [_i]),
    "sasnav_final_criterion_name": (c_char_p, [_i]),
    "sasnav_search_grid_name": (c_char_p, [_i]),
    "sasnav_verdict_rank": (_i, [_i]),
    "sasnav_pair_create": (_i, [_P(SystemC), _P(SensorArrayC), _P(Window), _P(PairOpts),
                                _P(c_void_p)]),
    "sasnav_pair_set_data": (_i, [c_void_p, cfloat_p, cfloat_p, Pose]),
    "sasnav_pair_set_data_lags": (_i, [c_void_p, cfloat_p, cfloat_p, Pose, _d, _d]),
    "sasnav_pair_set_data_run": (_i, [c_void_p, _P(RunC), _i, _i, cfloat_p, cfloat_p, Pose, _P(_d)]),
    "sasnav_run_tx_yaw": (_i, [_P(RunC), _d, _P(_d)]),
    "sasnav_pair_estimate": (_i, [c_void_p, _P(PairResult)]),
    "sasnav_pair_estimate_from": (_i, [c_void_p, Pose, _P(PairResult)]),
    "sasnav_pair_result_carry": (_v, [_P(PairResult), _P(PairResult)]),
    "sasnav_pair_rejudge": (_v, [c_void_p, _P(PairResult)]),
    "sasnav_run_tx_yaw_from_estimate": (_i, [_P(RunC), Pose, _d, _P(_d)]),
    "sasnav_pair_destroy": (_v, [c_void_p]),
    # dpca.h, navigate.h
    "sasnav_dpca_default_opts": (_v, [_P(DpcaOpts)]),
    "sasnav_navigate_default_opts": (_v, [_P(NavigateOpts)]),
    "sasnav_resolution_name": (c_char_p, [_i]),
    "sasnav_navigate": (_i, [_P(RunC), _P(NavigateOpts), _P(NavigationC)]),
    "sasnav_navigate_part": (_i, [_P(RunC), _P(NavigateOpts), _i, _i, _P(_P(PairRecord)), _P(_i)]),
    "sasnav_navigation_free": (_v, [_P(NavigationC)]),
    # virtual.h
    "sasnav_virtual_default_opts": (_v, [_P(VirtualOpts)]),
    "sasnav_navigate_virtual": (_i, [_P(RunC), _P(VirtualOpts), _P(VirtualNavigationC)]),
    "sasnav_virtual_navigation_free": (_v, [_P(VirtualNavigationC)]),
}


def declare(lib):
    """Sets restype and argtypes of every function of PROTOTYPES on the
    loaded library; raises OSError naming the first missing symbol."""
    for name, (restype, argtypes) in PROTOTYPES.items():
        try:
            fn = getattr(lib, name)
        except AttributeError:
            raise OSError(f"{lib._name}: symbol {name} not found (library too old?)") from None
        fn.restype = restype
        fn.argtypes = argtypes
    return lib


assert ctypes.sizeof(c_double) == 8
