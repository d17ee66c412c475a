"""The Python API: runs, navigation, images, simulation, pair estimates,
navigation of runs and imaging, over the C library (ctypes).

Every C allocation is released with the library's own function
(sasnav_run_free, sasnav_navigation_free, sasnav_pair_destroy,
sasnav_op_destroy, sasnav_scene_free; free() for the two buffers io.h
documents as malloc'ed) before the function returns; the objects returned
hold numpy arrays owned by Python.
"""

import contextlib
import ctypes
import math
from collections import namedtuple
from dataclasses import dataclass, field
from typing import List, Optional

import numpy as np

from . import _cdefs as C
from ._lib import Error, c_free, check, io_lock, lib, path_arg

__all__ = [
    "POSE_DTYPE", "PING_POSE_DTYPE", "Pose", "System", "SensorArray", "Aiding", "Run",
    "Grid", "Image", "NavData", "Scenario", "Candidate", "PairEstimate", "NavigatedPair",
    "Navigation", "library_version", "read_run", "write_run", "read_nav", "write_nav",
    "read_image", "write_image", "scenario", "simulate", "estimate_pair", "navigate",
    "image", "ping_poses", "centroids", "default_grid", "VirtualPair", "VirtualNavigation",
    "navigate_virtual",
]

# ---------------------------------------------------------------------------
# Poses

#: numpy dtype of sasnav_pose (x, y, theta), the C memory layout.
POSE_DTYPE = np.dtype([("x", "<f8"), ("y", "<f8"), ("theta", "<f8")])
#: numpy dtype of sasnav_ping_pose (transmitter pose, array pose).
PING_POSE_DTYPE = np.dtype([("tx", POSE_DTYPE), ("array", POSE_DTYPE)])

assert POSE_DTYPE.itemsize == ctypes.sizeof(C.Pose)
assert PING_POSE_DTYPE.itemsize == ctypes.sizeof(C.PingPose)


class Pose(namedtuple("Pose", "x y theta")):
    """An SE(2) pose or a motion error: (x, y, theta); for motion errors
    x is the surge (m), y the sway (m), theta the yaw (rad)."""

    __slots__ = ()

    @property
    def surge(self):
        return self.x

    @property
    def sway(self):
        return self.y

    @property
    def yaw(self):
        return self.theta


def _pose(c):
    return Pose(c.x, c.y, c.theta)


def _cpose(value, what="pose"):
    try:
        x, y, t = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} needs three numbers (x, y, theta), got {value!r}") from None
    return C.Pose(x, y, t)


def ping_poses(value, n=None, what="navigation"):
    """Ping poses as a contiguous PING_POSE_DTYPE array: accepts such an
    array, or floats shaped [n][2][3] or [n][6] ((tx x, y, theta), (array x,
    y, theta) per ping)."""
    a = np.asarray(value)
    if a.dtype.names:
        if a.dtype != PING_POSE_DTYPE:
            try:
                a = a.astype(PING_POSE_DTYPE)
            except (TypeError, ValueError):
                raise ValueError(f"{what}: structured array of dtype {a.dtype} is not ping poses") from None
        a = np.ascontiguousarray(a.reshape(-1))
    else:
        a = np.asarray(a, dtype=np.float64)
        if a.ndim == 3 and a.shape[1:] == (2, 3):
            a = a.reshape(a.shape[0], 6)
        if a.ndim != 2 or a.shape[1] != 6:
            raise ValueError(f"{what}: expected ping poses shaped [n][2][3] or [n][6], got {a.shape}")
        a = np.ascontiguousarray(a).view(PING_POSE_DTYPE).reshape(-1)
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{what}: {a.shape[0]} poses for {n} pings")
    return a


def _copy_out(address, dtype, count):
    """A numpy copy of `count` items of `dtype` at a C address."""
    dtype = np.dtype(dtype)
    if count == 0:
        return np.zeros(0, dtype)
    if not address:
        raise Error(-11, "internal error: NULL array from the library", "internal error")
    buf = (ctypes.c_char * (dtype.itemsize * count)).from_address(address)
    return np.frombuffer(buf, dtype=dtype, count=count).copy()


def _addr(ptr):
    return ctypes.cast(ptr, ctypes.c_void_p).value


def _copy_in(address, array):
    array = np.ascontiguousarray(array)
    ctypes.memmove(address, array.ctypes.data, array.nbytes)


def _poses_ptr(a):
    return a.ctypes.data_as(ctypes.POINTER(C.PingPose))


# ---------------------------------------------------------------------------
# System, array, aiding, run

_TAPERS = {"none": 0, "hann": 1, "hamming": 2}
_ATTENUATIONS = {"exploding": 0, "spherical": 1, "none": 2}


@dataclass
class System:
    """The acoustic system (sasnav_system, model.h). taper: 0 none, 1 Hann,
    2 Hamming; attenuation: 0 exploding sources, 1 spherical, 2 none."""

    sound_speed: float
    f0: float
    bandwidth: float
    sample_rate: float
    taper: int = 0
    attenuation: int = 0
    beam_pattern: int = 1

    @classmethod
    def default(cls):
        """The paper-pair system (sasnav_system_default)."""
        s = C.SystemC()
        lib().sasnav_system_default(ctypes.byref(s))
        return cls._from_c(s)

    @property
    def wavelength(self):
        return self.sound_speed / self.f0

    @classmethod
    def _from_c(cls, s):
        return cls(s.sound_speed, s.f0, s.bandwidth, s.sample_rate, s.taper, s.attenuation,
                   s.beam_pattern)

    def _to_c(self):
        def enum(v, names, what):
            if isinstance(v, str):
                if v not in names:
                    raise ValueError(f"{what} is one of {', '.join(names)} (got {v!r})")
                return names[v]
            return int(v)
        return C.SystemC(float(self.sound_speed), float(self.f0), float(self.bandwidth),
                         float(self.sample_rate), enum(self.taper, _TAPERS, "taper"),
                         enum(self.attenuation, _ATTENUATIONS, "attenuation"),
                         int(self.beam_pattern))


@dataclass
class SensorArray:
    """The sensor head (sasnav_array, geometry.h): receiver positions along
    the array axis (rx_u, m, relative to the midpoint), aperture lengths and
    heights above the scene plane. `sizes`, when given, is an [n_rx, 4]
    array of each channel's own (rx_length, tx_length, rx_height,
    tx_height) (sasnav_array_set_sizes: e.g. receivers at several heights);
    the four scalars are then the channels' largest lengths and mean heights
    as the library sets them."""

    rx_u: np.ndarray
    rx_length: float = 0.0
    tx_length: float = 0.0
    rx_height: float = 0.0
    tx_height: float = 0.0
    sizes: Optional[np.ndarray] = None

    @classmethod
    def uniform(cls, n, spacing, length, tx_length):
        """n receivers spaced `spacing` (sasnav_array_uniform)."""
        a = C.SensorArrayC()
        check(lib().sasnav_array_uniform(ctypes.byref(a), int(n), float(spacing), float(length),
                                         float(tx_length)))
        return cls._from_c(a)

    @property
    def n_rx(self):
        return int(np.asarray(self.rx_u).shape[0])

    @classmethod
    def _from_c(cls, a):
        n = max(0, min(a.n_rx, C.MAX_RX))
        sizes = None
        if a.per_channel:
            sizes = np.array([[a.size[l].rx_length, a.size[l].tx_length, a.size[l].rx_height,
                               a.size[l].tx_height] for l in range(n)], dtype=np.float64)
        return cls(np.array(a.rx_u[:n], dtype=np.float64), a.rx_length, a.tx_length,
                   a.rx_height, a.tx_height, sizes)

    def _to_c(self):
        u = np.asarray(self.rx_u, dtype=np.float64).reshape(-1)
        if not 1 <= u.shape[0] <= C.MAX_RX:
            raise ValueError(f"an array has 1 to {C.MAX_RX} receivers (got {u.shape[0]})")
        a = C.SensorArrayC()
        a.n_rx = u.shape[0]
        a.rx_u[: u.shape[0]] = u.tolist()
        a.rx_length, a.tx_length = float(self.rx_length), float(self.tx_length)
        a.rx_height, a.tx_height = float(self.rx_height), float(self.tx_height)
        if self.sizes is not None:
            z = np.asarray(self.sizes, dtype=np.float64)
            if z.shape != (u.shape[0], 4):
                raise ValueError(f"sizes must be [n_rx, 4] = [{u.shape[0]}, 4] "
                                 f"(rx_length, tx_length, rx_height, tx_height), got {list(z.shape)}")
            zc = (C.ChannelSizeC * u.shape[0])()
            for l in range(u.shape[0]):
                zc[l].rx_length, zc[l].tx_length, zc[l].rx_height, zc[l].tx_height = z[l].tolist()
            check(lib().sasnav_array_set_sizes(ctypes.byref(a), zc))
        return a

    def min_rx_length(self):
        """The smallest nonzero receiver aperture (0: all omnidirectional)."""
        d = [float(self.rx_length)] if self.sizes is None else \
            [float(v) for v in np.asarray(self.sizes)[:, 0]]
        d = [v for v in d if v > 0]
        return min(d) if d else 0.0


@dataclass
class Aiding:
    """Aiding measurements of a run (sasnav_aiding, run.h): row p describes
    the ping interval ending at ping p. yaw_rate* and velocity* may be None
    (no gyro / no DVL); velocity and velocity_sigma are shaped [n_pings][2]."""

    time: np.ndarray
    yaw_rate: Optional[np.ndarray] = None
    yaw_rate_sigma: Optional[np.ndarray] = None
    velocity: Optional[np.ndarray] = None
    velocity_sigma: Optional[np.ndarray] = None


@dataclass(eq=False)
class Run:
    """A run: raw data (complex64, [ping][rx][sample]), the system, the
    array, the sample window start t0 (s after transmission), the
    navigation to process with (`nav`, PING_POSE_DTYPE [n_pings]) and the
    true poses (`truth`, or None), the nominal ping spacing (m), speed (m/s),
    EPCA Tx-array offset tx_lag (m), range of interest (m), the aiding
    measurements (or None), and the channels' offsets (`channel_offset`,
    PING_POSE_DTYPE [n_rx]: each channel's transmitter and array pose
    relative to its ping's, sasnav_channel_poses; None for one transmitter
    and N receivers; file format version 2)."""

    raw: np.ndarray
    system: System
    array: SensorArray
    t0: float
    nav: np.ndarray
    truth: Optional[np.ndarray] = None
    ping_spacing: float = 0.0
    speed: float = 0.0
    tx_lag: float = 0.0
    range_of_interest: float = 0.0
    aiding: Optional[Aiding] = None
    channel_offset: Optional[np.ndarray] = None

    @property
    def n_pings(self):
        return int(self.raw.shape[0])

    @property
    def n_rx(self):
        return int(self.raw.shape[1])

    @property
    def n_samples(self):
        return int(self.raw.shape[2])

    @property
    def times(self):
        """Sample times t0 + m / sample_rate, s after transmission."""
        return self.t0 + np.arange(self.n_samples) / self.system.sample_rate

    @property
    def centroids(self):
        """PCA centroids of the navigation's pings (POSE_DTYPE [n_pings])."""
        return centroids(self.nav)

    def subset(self, pings, channels=None):
        """A new run of the given pings (and channels), as sasnav_run_subset."""
        pings = np.ascontiguousarray(pings, dtype=np.intc).reshape(-1)
        ch = None if channels is None else np.ascontiguousarray(channels, dtype=np.intc).reshape(-1)
        out = ctypes.POINTER(C.RunC)()
        with _c_run(self) as r:
            check(lib().sasnav_run_subset(
                r, pings.ctypes.data_as(ctypes.POINTER(ctypes.c_int)), pings.shape[0],
                None if ch is None else ch.ctypes.data_as(ctypes.POINTER(ctypes.c_int)),
                0 if ch is None else ch.shape[0], ctypes.byref(out)))
        return _take_run(out)


def centroids(nav):
    """PCA centroids (POSE_DTYPE) of ping poses (sasnav_ping_centroid)."""
    nav = ping_poses(nav)
    L = lib()
    out = np.zeros(nav.shape[0], POSE_DTYPE)
    for i in range(nav.shape[0]):
        c = L.sasnav_ping_centroid(ctypes.cast(nav.ctypes.data + i * nav.itemsize,
                                               ctypes.POINTER(C.PingPose)))
        out[i] = (c.x, c.y, c.theta)
    return out


def _run_from_c(r):
    """A Python Run holding copies of a C run's arrays."""
    n, nrx, ns = r.n_pings, r.array.n_rx, r.win.n_samples
    raw = _copy_out(r.raw, np.complex64, n * nrx * ns).reshape(n, nrx, ns)
    nav = _copy_out(_addr(r.nav), PING_POSE_DTYPE, n)
    truth = _copy_out(_addr(r.truth), PING_POSE_DTYPE, n) if r.truth else None
    aiding = None
    if r.aiding:
        a = r.aiding.contents

        def arr(ptr, count, shape):
            return _copy_out(_addr(ptr), np.float64, count).reshape(shape) if ptr else None

        aiding = Aiding(arr(a.time, n, (n,)), arr(a.yaw_rate, n, (n,)),
                        arr(a.yaw_rate_sigma, n, (n,)), arr(a.velocity, 2 * n, (n, 2)),
                        arr(a.velocity_sigma, 2 * n, (n, 2)))
    off = _copy_out(_addr(r.channel_offset), PING_POSE_DTYPE, nrx) if r.channel_offset else None
    return Run(raw, System._from_c(r.sys), SensorArray._from_c(r.array), r.win.t0, nav, truth,
               r.ping_spacing, r.speed, r.tx_lag, r.range_of_interest, aiding, off)


def _take_run(ptr):
    """Copies a C run into Python and frees it (sasnav_run_free)."""
    try:
        return _run_from_c(ptr.contents)
    finally:
        lib().sasnav_run_free(ptr)


@contextlib.contextmanager
def _c_run(run):
    """A C copy of a Python Run (sasnav_run_alloc), freed on exit."""
    if not isinstance(run, Run):
        raise TypeError(f"expected a sasnav.Run, got {type(run).__name__}")
    raw = np.asarray(run.raw)
    if raw.ndim != 3:
        raise ValueError(f"run.raw must be shaped [ping][rx][sample], got {raw.shape}")
    n, nrx, ns = raw.shape
    if nrx != run.array.n_rx:
        raise ValueError(f"run.raw has {nrx} channels but the array {run.array.n_rx} receivers")
    nav = ping_poses(run.nav, n, "run.nav")
    truth = None if run.truth is None else ping_poses(run.truth, n, "run.truth")
    raw = np.ascontiguousarray(raw, dtype=np.complex64)
    L = lib()
    sys_c, arr_c = run.system._to_c(), run.array._to_c()
    win = C.Window(float(run.t0), ns)
    ptr = ctypes.POINTER(C.RunC)()
    check(L.sasnav_run_alloc(ctypes.byref(sys_c), ctypes.byref(arr_c), ctypes.byref(win), n,
                             int(truth is not None), ctypes.byref(ptr)))
    try:
        r = ptr.contents
        _copy_in(r.raw, raw)
        _copy_in(_addr(r.nav), nav)
        if truth is not None:
            _copy_in(_addr(r.truth), truth)
        r.ping_spacing, r.speed = float(run.ping_spacing), float(run.speed)
        r.tx_lag, r.range_of_interest = float(run.tx_lag), float(run.range_of_interest)
        if run.channel_offset is not None:
            off = ping_poses(run.channel_offset, nrx, "run.channel_offset")
            check(L.sasnav_run_set_channel_offset(
                ptr, ctypes.cast(off.ctypes.data, ctypes.POINTER(C.PingPose))))
        if run.aiding is not None:
            a = run.aiding
            gyro = a.yaw_rate is not None
            dvl = a.velocity is not None
            check(L.sasnav_run_alloc_aiding(ptr, int(gyro), int(dvl)))
            ac = r.aiding.contents

            def put(dst, value, shape, what):
                v = np.asarray(value, dtype=np.float64)
                if v.shape != shape:
                    raise ValueError(f"run.aiding.{what} must be shaped {shape}, got {v.shape}")
                _copy_in(_addr(dst), v)

            put(ac.time, a.time, (n,), "time")
            if gyro:
                put(ac.yaw_rate, a.yaw_rate, (n,), "yaw_rate")
                put(ac.yaw_rate_sigma, a.yaw_rate_sigma, (n,), "yaw_rate_sigma")
            if dvl:
                put(ac.velocity, a.velocity, (n, 2), "velocity")
                put(ac.velocity_sigma, a.velocity_sigma, (n, 2), "velocity_sigma")
        yield ptr
    finally:
        L.sasnav_run_free(ptr)


def library_version():
    """The C library's version string (sasnav_version())."""
    return lib().sasnav_version().decode()


def read_run(path):
    """Reads a run file (HDF5, docs/format.md) into a Run."""
    ptr = ctypes.POINTER(C.RunC)()
    with io_lock:
        check(lib().sasnav_run_read(path_arg(path), ctypes.byref(ptr)))
    return _take_run(ptr)


class StreamedRun:
    """A run file opened for streaming (sasnav_run_open): everything but
    the samples is held (n_pings, system, array, t0, nav, truth, ...), and
    each ping is read from the file when asked for (`ping(p)`, a complex64
    array [rx][sample]) or when `navigate` / `image` use it: a survey's run
    need not fit in memory. The file was checked ping by ping when opened.
    Close it with close() or use it in a `with` block."""

    def __init__(self, ptr):
        self._ptr = ptr
        r = ptr.contents
        self.system = System._from_c(r.sys)
        self.array = SensorArray._from_c(r.array)
        self.t0 = r.win.t0
        self.n_pings, self.n_rx, self.n_samples = r.n_pings, r.array.n_rx, r.win.n_samples
        self.nav = _copy_out(_addr(r.nav), PING_POSE_DTYPE, r.n_pings)
        self.truth = _copy_out(_addr(r.truth), PING_POSE_DTYPE, r.n_pings) if r.truth else None
        self.ping_spacing, self.speed = r.ping_spacing, r.speed
        self.tx_lag, self.range_of_interest = r.tx_lag, r.range_of_interest
        self.has_aiding = bool(r.aiding)
        self.channel_offset = (_copy_out(_addr(r.channel_offset), PING_POSE_DTYPE, r.array.n_rx)
                               if r.channel_offset else None)

    def _c(self):
        if self._ptr is None:
            raise ValueError("the streamed run is closed")
        return self._ptr

    def ping(self, p):
        """Ping p's samples, read from the file (complex64 [rx][sample])."""
        if int(p) != p or not 0 <= p < self.n_pings:
            raise ValueError(f"ping {p!r} out of range (the run has {self.n_pings} pings)")
        out = np.zeros((self.n_rx, self.n_samples), np.complex64)
        got = C.cfloat_p()
        with io_lock:
            check(lib().sasnav_run_get_ping(self._c(), int(p), out.ctypes.data, ctypes.byref(got)))
        return out

    @property
    def centroids(self):
        return centroids(self.nav)

    def close(self):
        if self._ptr is not None:
            with io_lock:
                lib().sasnav_run_free(self._ptr)
            self._ptr = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def open_run(path):
    """Opens a run file for streaming (a StreamedRun; sasnav_run_open)."""
    ptr = ctypes.POINTER(C.RunC)()
    with io_lock:
        check(lib().sasnav_run_open(path_arg(path), ctypes.byref(ptr)))
    return StreamedRun(ptr)


@contextlib.contextmanager
def _run_arg(run):
    """The C run of a Run (a copy, freed on exit) or of a StreamedRun (its
    own, holding the HDF5 lock: the library reads the file)."""
    if isinstance(run, StreamedRun):
        with io_lock:
            yield run._c()
    else:
        with _c_run(run) as r:
            yield r


def write_run(run, path):
    """Writes a Run as a run file (validated by the library first)."""
    with _c_run(run) as r, io_lock:
        check(lib().sasnav_run_write(path_arg(path), r))


# ---------------------------------------------------------------------------
# Navigation files


@dataclass
class NavData:
    """A navigation file: ping poses `nav` and optionally `truth`
    (PING_POSE_DTYPE [n_pings]) and `formal_sigma` (POSE_DTYPE [n_pings]:
    the navigation's formal standard deviations, /nav_sigma)."""

    nav: np.ndarray
    truth: Optional[np.ndarray] = None
    formal_sigma: Optional[np.ndarray] = None

    @property
    def n_pings(self):
        return int(self.nav.shape[0])


def read_nav(path):
    """Reads a navigation file (or the /nav and /truth of a run file)."""
    n = ctypes.c_int(0)
    nav = ctypes.POINTER(C.PingPose)()
    truth = ctypes.POINTER(C.PingPose)()
    try:
        with io_lock:
            check(lib().sasnav_nav_read(path_arg(path), ctypes.byref(n), ctypes.byref(nav),
                                        ctypes.byref(truth)))
        a = _copy_out(_addr(nav), PING_POSE_DTYPE, n.value)
        t = _copy_out(_addr(truth), PING_POSE_DTYPE, n.value) if truth else None
    finally:
        # io.h: allocated with malloc (no sasnav_ free function for them).
        c_free(_addr(nav))
        c_free(_addr(truth))
    sigma = ctypes.POINTER(C.Pose)()
    try:
        with io_lock:
            check(lib().sasnav_nav_read_sigma(path_arg(path), ctypes.byref(n), ctypes.byref(sigma)))
        sg = _copy_out(_addr(sigma), POSE_DTYPE, n.value) if sigma else None
    finally:
        c_free(_addr(sigma))
    if sg is not None and sg.shape[0] != a.shape[0]:
        raise Error(-4, f"{path}: the file changed while it was read", "format error")
    return NavData(a, t, sg)


def write_nav(nav, path, truth=None):
    """Writes a navigation file. `nav` is ping poses (see ping_poses), or a
    NavData / Navigation (its `nav`, its `formal_sigma` if it has them, and,
    unless `truth` is given, its `truth`)."""
    sigma = None
    if hasattr(nav, "nav"):
        if truth is None:
            truth = getattr(nav, "truth", None)
        sigma = getattr(nav, "formal_sigma", None)
        nav = nav.nav
    a = ping_poses(nav)
    t = None if truth is None else ping_poses(truth, a.shape[0], "truth")
    sg = None
    if sigma is not None:
        sg = np.ascontiguousarray(sigma, dtype=POSE_DTYPE)
        if sg.shape != (a.shape[0],):
            raise ValueError(f"formal_sigma needs {a.shape[0]} rows, got shape {sg.shape}")
    with io_lock:
        check(lib().sasnav_nav_write_sigma(path_arg(path), a.shape[0], _poses_ptr(a),
                                           None if t is None else _poses_ptr(t),
                                           None if sg is None else sg.ctypes.data_as(ctypes.POINTER(C.Pose))))


# ---------------------------------------------------------------------------
# Grids and images


@dataclass(frozen=True)
class Grid:
    """A rectangular image grid (sasnav_grid): pixel (iy, ix) at
    (x0 + ix dx, y0 + iy dy); images are [iy][ix] (rows along range y)."""

    x0: float
    y0: float
    dx: float
    dy: float
    nx: int
    ny: int

    @classmethod
    def make(cls, x_min, x_max, nx, y_min, y_max, ny):
        """nx x ny pixels covering [x_min, x_max] x [y_min, y_max]
        (sasnav_grid_make)."""
        g = C.GridC()
        check(lib().sasnav_grid_make(float(x_min), float(x_max), int(nx), float(y_min),
                                     float(y_max), int(ny), ctypes.byref(g)))
        return cls._from_c(g)

    @property
    def x(self):
        """Along-track pixel coordinates (nx), m."""
        return self.x0 + self.dx * np.arange(self.nx)

    @property
    def y(self):
        """Range pixel coordinates (ny), m."""
        return self.y0 + self.dy * np.arange(self.ny)

    @property
    def shape(self):
        return (self.ny, self.nx)

    @property
    def extent(self):
        """(left, right, bottom, top) of the pixels' edges, for matplotlib's
        imshow(..., origin="lower")."""
        return (self.x0 - self.dx / 2, self.x0 + (self.nx - 0.5) * self.dx,
                self.y0 - self.dy / 2, self.y0 + (self.ny - 0.5) * self.dy)

    @classmethod
    def _from_c(cls, g):
        return cls(g.x0, g.y0, g.dx, g.dy, g.nx, g.ny)

    def _to_c(self):
        g = C.GridC(float(self.x0), float(self.y0), float(self.dx), float(self.dy), int(self.nx),
                    int(self.ny))
        check(lib().sasnav_grid_check(ctypes.byref(g)))
        return g


def _as_grid(grid):
    if isinstance(grid, Grid):
        return grid
    try:
        x0, x1, nx, y0, y1, ny = grid
    except (TypeError, ValueError):
        raise ValueError("grid needs a sasnav.Grid or (x_min, x_max, nx, y_min, y_max, ny)") from None
    if int(nx) != nx or int(ny) != ny:
        raise ValueError("grid: nx and ny must be integers")
    return Grid.make(x0, x1, int(nx), y0, y1, int(ny))


@dataclass(eq=False)
class Image:
    """A complex image: `data` complex64 [ny][nx] on `grid`; `x`, `y` are
    its axes (m)."""

    data: np.ndarray
    grid: Grid

    @property
    def x(self):
        return self.grid.x

    @property
    def y(self):
        return self.grid.y

    def db(self, floor=-np.inf):
        """20 log10 |data| re its maximum (dB), clipped below at floor."""
        mag = np.abs(self.data)
        peak = mag.max() if mag.size else 0.0
        with np.errstate(divide="ignore"):
            out = 20 * np.log10(mag / peak) if peak > 0 else np.full(mag.shape, -np.inf)
        return np.maximum(out, floor)

    def peak(self):
        """(x, y) of the pixel of largest modulus, m."""
        iy, ix = np.unravel_index(np.argmax(np.abs(self.data)), self.data.shape)
        return float(self.x[ix]), float(self.y[iy])


def read_image(path):
    """Reads an image file (complex, converted to complex64 [ny][nx])."""
    g = C.GridC()
    buf = ctypes.c_void_p()
    try:
        with io_lock:
            check(lib().sasnav_image_read(path_arg(path), ctypes.byref(g), ctypes.byref(buf)))
        data = _copy_out(buf.value, np.complex64, g.nx * g.ny).reshape(g.ny, g.nx)
    finally:
        c_free(buf.value)  # io.h: "free with free()"
    return Image(data, Grid._from_c(g))


def write_image(image, path):
    """Writes an Image (its data is converted to complex64)."""
    if not isinstance(image, Image):
        raise TypeError(f"expected a sasnav.Image, got {type(image).__name__}")
    g = image.grid._to_c()
    data = np.ascontiguousarray(image.data, dtype=np.complex64)
    if data.shape != (g.ny, g.nx):
        raise ValueError(f"image data shaped {data.shape} on a grid of {(g.ny, g.nx)} pixels")
    with io_lock:
        check(lib().sasnav_image_write(path_arg(path), ctypes.byref(g), data.ctypes.data))


# ---------------------------------------------------------------------------
# Scenarios and simulation


class Scenario:
    """A simulated scenario (sasnav_scenario, sim.h): a preset with a YAML
    config's overrides. The ctypes struct is `c` (every field of the
    header); the properties below cover the common ones."""

    def __init__(self, preset="paper-trajectory", config=None):
        self.c = C.ScenarioC()
        check(lib().sasnav_scenario_preset(str(preset).encode(), ctypes.byref(self.c)))
        if config is not None:
            with io_lock:
                check(lib().sasnav_config_load(path_arg(config), ctypes.byref(self.c)))

    @property
    def name(self):
        return self.c.name.decode("utf-8", "replace")

    @property
    def n_pings(self):
        return self.c.traj.n_pings

    @n_pings.setter
    def n_pings(self, n):
        self.c.traj.n_pings = int(n)

    @property
    def snr_db(self):
        return self.c.snr_db

    @snr_db.setter
    def snr_db(self, v):
        self.c.snr_db = float(v)

    @property
    def system(self):
        return System._from_c(self.c.sys)

    @property
    def array(self):
        return SensorArray._from_c(self.c.array)

    @property
    def range_of_interest(self):
        return self.c.range_of_interest

    @property
    def targets(self):
        """Point targets [n][3]: x (m), y (m), amplitude."""
        n = max(0, min(self.c.n_targets, C.MAX_TARGETS))
        return np.array([self.c.target_x[:n], self.c.target_y[:n], self.c.target_amp[:n]],
                        dtype=np.float64).T.reshape(n, 3)

    @property
    def image_grid(self):
        """The scenario's default imaging grid."""
        return Grid._from_c(self.c.image_grid)

    def seed(self, seed):
        """Seeds every random draw from one number (sasnav_scenario_seed)."""
        seed = int(seed)
        if seed < 0:
            raise ValueError("seed must be >= 0")
        lib().sasnav_scenario_seed(ctypes.byref(self.c), seed)

    def check(self):
        check(lib().sasnav_scenario_check(ctypes.byref(self.c)))

    def write(self, path):
        """Writes the scenario as a YAML config (every key)."""
        with io_lock:
            check(lib().sasnav_config_write(path_arg(path), ctypes.byref(self.c)))

    def __repr__(self):
        return f"<sasnav.Scenario {self.name!r}: {self.n_pings} pings>"


def scenario(preset="paper-trajectory", config=None):
    """A Scenario from a preset ("paper-pair", "paper-trajectory", "point")
    and optionally a YAML config (docs/config.md) applied on top."""
    return Scenario(preset, config)


def _op_opts(threads=0, tolerance=None):
    o = C.OpOpts()
    lib().sasnav_op_default_opts(ctypes.byref(o))
    o.nthreads = int(threads)
    if tolerance is not None:
        o.tolerance = float(tolerance)
    return o


def simulate(preset=None, config=None, *, scenario=None, seed=None, snr=None, error=None,
             aiding=False, n_pings=None, threads=0):
    """Simulates a run, as `sasnav simulate`: a preset (default
    "paper-trajectory") and/or a YAML config, or a Scenario; `seed` seeds
    every draw, `snr` (dB, math.inf for noise-free) the noise, `error`
    (surge, sway, yaw) the motion error of ping 1 relative to ping 0,
    `aiding` adds gyro and DVL measurements, `n_pings` overrides the
    number of pings. Returns a Run (nav: nominal poses, truth: true ones)."""
    if scenario is not None:
        if preset is not None or config is not None:
            raise ValueError("give a scenario or a preset / config, not both")
        sc = Scenario.__new__(Scenario)
        sc.c = C.ScenarioC.from_buffer_copy(scenario.c)
    else:
        sc = Scenario(preset or "paper-trajectory", config)
    if seed is not None:
        sc.seed(seed)
    if aiding:
        sc.c.aiding.enabled = 1
    if snr is not None:
        sc.snr_db = float(snr)
    if n_pings is not None:
        sc.n_pings = n_pings
    if error is not None:
        if sc.n_pings < 2:
            raise ValueError("error needs at least two pings")
        sc.c.traj.has_pair_error = 1
        sc.c.traj.pair_q = 1
        sc.c.traj.pair_error = _cpose(error, "error")
    sc.check()
    L = lib()
    scene = ctypes.POINTER(C.SceneC)()
    try:
        if sc.c.scene_kind == C.CONSTANTS["SASNAV_SCENE_FILE"]:
            img = read_image(sc.c.scene_file.decode())
            g = img.grid
            data = np.ascontiguousarray(img.data, dtype=np.complex64)
            # as `sasnav simulate`: one scatterer per pixel, jittered 0.3 px
            check(L.sasnav_scene_from_image(g.x0, g.y0, g.dx, g.dy, g.nx, g.ny, data.ctypes.data,
                                            0.3, sc.c.ripples.seed, ctypes.byref(scene)))
        oo = _op_opts(threads)
        run = ctypes.POINTER(C.RunC)()
        check(L.sasnav_simulate(ctypes.byref(sc.c), scene if scene else None, ctypes.byref(oo),
                                ctypes.byref(run)))
    finally:
        L.sasnav_scene_free(scene)
    return _take_run(run)


# ---------------------------------------------------------------------------
# Options


_NORMS = {"max": 0, "p": 1, "q": 2, "none": 3}
_METHODS = {"subspace": 0, "dpca": 1, "aiding": 2}
_METHOD_NAMES = {v: k for k, v in _METHODS.items()}
_SPEED_LAGS = {"none": 0, "dvl": 1, "pairs": 2}
_TX_YAW = {"none": 0, "auto": 1, "pairs": 2}
_FINALS = {"eta": 0, "joint": 1, "auto": 2}  # sasnav_final_criterion
_SEARCH_GRIDS = {"auto": 0, "fine": 1, "coarse": 2}  # sasnav_search_grid
_ENUMS = {"norm": _NORMS, "method": _METHODS, "speed_lags": _SPEED_LAGS, "tx_yaw": _TX_YAW,
          "final_criterion": _FINALS, "search_grid": _SEARCH_GRIDS}
# compact_pairs: the Python navigation reads `pairs` directly (packed pairs
# save memory on long runs, where open_run's navigate_part serves).
_NOT_SETTABLE = {"reuse", "progress", "progress_user", "compact_pairs", "done", "n_done"}


def _set_fields(struct, opts, what):
    fields = dict(struct._fields_)
    for key, value in opts.items():
        if key not in fields or key in _NOT_SETTABLE:
            known = ", ".join(k for k in fields if k not in _NOT_SETTABLE)
            raise ValueError(f"unknown {what} option {key!r} (known: {known})")
        ftype = fields[key]
        if ftype is C.Pose:
            setattr(struct, key, _cpose(value, key))
        elif isinstance(ftype, type) and issubclass(ftype, ctypes.Structure):
            if not isinstance(value, dict):
                raise ValueError(f"{what} option {key!r} takes a dict of its fields")
            _set_fields(getattr(struct, key), value, f"{what}.{key}")
        elif ftype is ctypes.c_int:
            if key in _ENUMS and isinstance(value, str):
                if value not in _ENUMS[key]:
                    raise ValueError(f"{key} is one of {', '.join(_ENUMS[key])} (got {value!r})")
                value = _ENUMS[key][value]
            if isinstance(value, float) and not value.is_integer():
                raise ValueError(f"{what} option {key!r} needs an integer (got {value!r})")
            try:
                setattr(struct, key, int(value))
            except (TypeError, ValueError):
                raise ValueError(f"{what} option {key!r} needs an integer (got {value!r})") from None
        else:
            try:
                setattr(struct, key, float(value))
            except (TypeError, ValueError):
                raise ValueError(f"{what} option {key!r} needs a number (got {value!r})") from None


def _pair_opts(opts, run):
    po = C.PairOpts()
    lib().sasnav_pair_default_opts(ctypes.byref(po))
    # as `sasnav pair`: the run's range of interest and Tx-array offset
    po.range = run.range_of_interest if run.range_of_interest > 0 else 10.0
    po.tx_lag = run.tx_lag
    opts = dict(opts)
    if "threads" in opts:
        opts["nthreads"] = opts.pop("threads")
    _set_fields(po, opts, "pair")
    # the coarse stages never use more iterations than the final one
    if "coarse_k" not in opts:
        po.coarse_k = min(po.coarse_k, po.k)
    if "coarse_i" not in opts:
        po.coarse_i = min(po.coarse_i, po.i)
    return po


# ---------------------------------------------------------------------------
# Pair estimates


Candidate = namedtuple("Candidate", "error zeta_scan zeta eta refined same_as chosen")
Candidate.__doc__ = """A candidate of the estimator's search (sasnav_pair_candidate):
error (Pose), zeta_scan, zeta, eta (NaN where not evaluated), refined (bool),
same_as (index of an earlier candidate it converged to, or None), chosen."""


def _verdict_name(v):
    return lib().sasnav_verdict_name(int(v)).decode()


def _status_name(rc):
    return "ok" if rc == 0 else lib().sasnav_strerror(int(rc)).decode()


@dataclass
class PairEstimate:
    """The estimate of the motion error (displacement minus nominal; surge,
    sway, yaw) of ping q relative to ping p (sasnav_pair_result).

    error, displacement, nominal, global_stage, zeta_stage: Pose;
    truth: the true motion error when the run holds the truth (else None);
    zeta, eta: the error functions at the estimate; final_criterion: the
    final stage's ("eta", "joint"; "none" for DPCA); search_grid: the
    search stages' grid ("coarse", "fine"; "none" for DPCA); verdict: "ok",
    "ambiguous", "failed", "no_overlap" or (DPCA) "unchecked"; margin (inf: no other
    candidate); coincidence: True where the estimate sits at a phase-centre
    coincidence on a compact scene, where its surge is not resolved (the
    verdict is then "ambiguous" at best); contrast, contrast_q: the intensity
    contrasts of p's reconstruction and of q's at the estimate, the larger of
    which decided between the speckle and the compact-scene rules (0 for
    DPCA); equalised: True where the search's criteria were weighted by the
    images' smoothed intensity (pair option equalise, on a scene
    speckle-like at the prior where a feature stands out); equalise_peak:
    the gate's peak of the smoothed intensity over its mean (at least 8 to
    be equalised; 0 where the weights were not made); candidates: list of Candidate; status: "ok" or the
    estimator's status text; result: the C struct (every field)."""

    p: int
    q: int
    error: Pose
    displacement: Pose
    nominal: Pose
    truth: Optional[Pose]
    global_stage: Pose
    zeta_stage: Pose
    zeta: float
    eta: float
    overlap: float
    ambiguity: float
    margin: float
    verdict: str
    status: str
    candidates: List[Candidate]
    chosen: int
    evaluations: int
    applications: int
    seconds: float
    final_criterion: str
    search_grid: str
    coincidence: bool
    contrast: float
    contrast_q: float
    equalised: bool
    equalise_peak: float
    result: C.PairResult = field(repr=False)


def _final_name(r):
    # DPCA's estimates (unchecked) and pairs never estimated have no final stage
    if r.verdict == 4 or r.evaluations == 0:
        return "none"
    return lib().sasnav_final_criterion_name(int(r.final_criterion)).decode()


def _search_grid_name(r):
    # as _final_name: no search ran for DPCA's estimates or unestimated pairs
    if r.verdict == 4 or r.evaluations == 0:
        return "none"
    return lib().sasnav_search_grid_name(int(r.search_grid)).decode()


def _estimate_from_c(r, p, q, nominal, truth):
    cands = []
    for k in range(max(0, min(r.n_candidates, C.PAIR_MAX_CANDIDATES))):
        c = r.candidates[k]
        cands.append(Candidate(_pose(c.error), c.zeta_scan, c.zeta, c.eta, bool(c.refined),
                               None if c.same_as < 0 else c.same_as, k == r.chosen))
    return PairEstimate(p, q, _pose(r.error), _pose(r.displacement), nominal, truth,
                        _pose(r.global_stage), _pose(r.zeta_stage), r.zeta, r.eta, r.overlap,
                        r.ambiguity, r.margin, _verdict_name(r.verdict),
                        "ok" if r.status == 0 else _status_name(r.status), cands, r.chosen,
                        r.evaluations, r.applications, r.seconds,
                        _final_name(r),
                        _search_grid_name(r),
                        bool(r.coincidence),
                        r.contrast,
                        r.contrast_q,
                        bool(r.equalised),
                        float(r.equalise_peak),
                        C.PairResult.from_buffer_copy(r))


def _motion_error(nav, truth, p, q):
    """Nominal displacement of q relative to p, and the true motion error."""
    L = lib()
    nav = ping_poses(nav)
    np_ = ctypes.POINTER(C.PingPose)

    def at(a, i):
        return ctypes.cast(a.ctypes.data + i * a.itemsize, np_)

    nominal = L.sasnav_ping_displacement(at(nav, p), at(nav, q))
    true_err = None
    if truth is not None:
        t = ping_poses(truth)
        d = L.sasnav_ping_displacement(at(t, p), at(t, q))
        true_err = Pose(d.x - nominal.x, d.y - nominal.y,
                        L.sasnav_wrap_angle(d.theta - nominal.theta))
    return nominal, true_err


def estimate_pair(run, p=0, q=1, *, prior_start=None, lags=None, **opts):
    """Estimates the motion error of ping q relative to ping p of `run`
    with the subspace-intersection estimator (as `sasnav pair`).

    opts: any field of sasnav_pair_opts (estimator.h) by name, e.g. k, i,
    prior=(s, w, y), box=(s, w, y), yaw_sigma, surge_sigma, fix_yaw,
    global_stage=0, range, range_extent, cross_extent, norm ("max", "p",
    "q", "none"), op=dict(tolerance=...), threads (= nthreads),
    final_criterion ("auto", "eta", "joint"). range and
    tx_lag default to the run's range of interest and Tx-array offset.
    lags=(lag_p, lag_q): per-ping Tx-array offsets
    (sasnav_pair_set_data_lags). prior_start=(s, w, y): local stages only,
    from that motion error (sasnav_pair_estimate_from).
    Returns a PairEstimate."""
    if not isinstance(run, Run):
        raise TypeError(f"expected a sasnav.Run, got {type(run).__name__}")
    n = run.n_pings
    for name, v in (("p", p), ("q", q)):
        if int(v) != v or not 0 <= v < n:
            raise ValueError(f"ping index {name}={v!r} out of range (the run has {n} pings)")
    p, q = int(p), int(q)
    if p == q:
        raise ValueError(f"p and q name the same ping ({p})")
    po = _pair_opts(opts, run)
    nominal, truth = _motion_error(run.nav, run.truth, p, q)
    raw = np.ascontiguousarray(run.raw, dtype=np.complex64)
    L = lib()
    sys_c, arr_c = run.system._to_c(), run.array._to_c()
    win = C.Window(float(run.t0), run.n_samples)
    pair = ctypes.c_void_p()
    res = C.PairResult()
    try:
        check(L.sasnav_pair_create(ctypes.byref(sys_c), ctypes.byref(arr_c), ctypes.byref(win),
                                   ctypes.byref(po), ctypes.byref(pair)))
        dp, dq = raw[p].ctypes.data, raw[q].ctypes.data
        yaw = None
        if run.channel_offset is not None:
            # channels with transmitters of their own: their layouts (and the
            # gyro's transmitter yaw), as `sasnav pair` / navigate
            if lags is not None:
                raise ValueError("lags do not apply to a run with channel offsets (its layouts give them)")
            with _c_run(run) as r:
                rc = r.contents
                if rc.aiding and rc.aiding.contents.yaw_rate:
                    yaw = np.zeros(n)
                    check(L.sasnav_run_tx_yaw(r, po.range, yaw.ctypes.data_as(ctypes.POINTER(ctypes.c_double))))
                check(L.sasnav_pair_set_data_run(
                    pair, r, p, q, dp, dq, nominal,
                    None if yaw is None else yaw.ctypes.data_as(ctypes.POINTER(ctypes.c_double))))
        elif lags is None:
            check(L.sasnav_pair_set_data(pair, dp, dq, nominal))
        else:
            lp, lq = (float(v) for v in lags)
            check(L.sasnav_pair_set_data_lags(pair, dp, dq, nominal, lp, lq))
        if prior_start is None:
            check(L.sasnav_pair_estimate(pair, ctypes.byref(res)))
        else:
            check(L.sasnav_pair_estimate_from(pair, _cpose(prior_start, "prior_start"),
                                              ctypes.byref(res)))
        if run.channel_offset is not None and yaw is None and res.verdict == 0:
            # no gyro: the transmitters' turn from this "ok" estimate, and
            # the estimate again from it (as `sasnav pair`)
            again = C.PairResult()
            dptr = ctypes.POINTER(ctypes.c_double)
            yaw2 = np.zeros(n)
            with _c_run(run) as r:
                if L.sasnav_run_tx_yaw_from_estimate(r, res.displacement, ctypes.c_double(po.range),
                                                     yaw2.ctypes.data_as(dptr)) == 0:
                    check(L.sasnav_pair_set_data_run(pair, r, p, q, dp, dq, nominal, yaw2.ctypes.data_as(dptr)))
                    check(L.sasnav_pair_estimate_from(pair, res.error, ctypes.byref(again)))
                    if again.verdict == 0:
                        # judged again with the first's margin (as `sasnav pair`)
                        L.sasnav_pair_result_carry(ctypes.byref(res), ctypes.byref(again))
                        L.sasnav_pair_rejudge(pair, ctypes.byref(again))
                        res = again
    finally:
        L.sasnav_pair_destroy(pair)
    return _estimate_from_c(res, p, q, _pose(nominal), truth)


# ---------------------------------------------------------------------------
# Navigation


@dataclass
class NavigatedPair:
    """One pair of a navigation (sasnav_navigate_pair): `fused` is the motion
    error the trajectory is built from; `estimate` the estimator's result
    after the joint resolution, `first_estimate` before it; `status` "ok" or
    the failure; verdict / first_verdict; resolution ("kept", "candidate",
    "re-estimated", "bridged"); truth and error (fused - truth) when the run
    holds the truth; aiding and aiding_sigma when the aiding was used;
    eta_outlier: its eta exceeds the eta_outlier option times the run's
    median (its verdict is then "ambiguous" at best)."""

    p: int
    q: int
    status: str
    nominal: Pose
    fused: Pose
    verdict: str
    first_verdict: str
    resolution: str
    estimate: PairEstimate
    first_estimate: PairEstimate
    truth: Optional[Pose]
    error: Optional[Pose]
    aiding: Optional[Pose]
    aiding_sigma: Optional[Pose]
    eta_outlier: bool = False


@dataclass(eq=False)
class Navigation:
    """The result of navigate() (sasnav_navigation): estimated ping poses
    `nav` (PING_POSE_DTYPE) and PCA centroids `centroids` (POSE_DTYPE), the
    track angle removed by the alignment, the pairs, and, for runs with
    truth, truth_centroids, anchored (estimated poses moved so that the
    first centroid is the true one), cumulative and differential errors
    (POSE_DTYPE) and their rms (Pose). `truth` is the run's true ping poses
    (written by write_nav with nav, as `sasnav navigate` does)."""

    method: str
    n_pings: int
    nav: np.ndarray
    centroids: np.ndarray
    track_angle: float
    pairs: List[NavigatedPair]
    n_failed: int
    n_flagged: int
    n_resolved: int
    n_skipped: int
    aiding_used: bool
    lsq_iterations: int
    has_truth: bool
    truth: Optional[np.ndarray]
    truth_centroids: Optional[np.ndarray]
    anchored: Optional[np.ndarray]
    cumulative: Optional[np.ndarray]
    differential: Optional[np.ndarray]
    rms_cumulative: Optional[Pose]
    rms_differential: Optional[Pose]
    seconds: float
    seconds_per_pair: float
    pairs_per_second: float
    threads_over_pairs: int
    tx_yaw: str = "none"  # channels with transmitters of their own: where their turn
    #                       between transmission and reception came from:
    #                       "gyro", "pairs" (the pairs' own yaw) or "none"
    eta_median: float = math.nan  # the run's median pair eta (NaN: not computed)
    n_eta_outliers: int = 0  # pairs over eta_outlier x eta_median
    # formal standard deviations of the centroids relative to the first
    # (POSE_DTYPE: along, across the aligned track, yaw): the smoother's
    # posterior carried through the chain; None without a smoother, with long
    # baselines or for DPCA (docs/navigation.md, "Formal standard deviations")
    formal_sigma: Optional[np.ndarray] = None

    def placed(self, first_pose):
        """The estimated ping poses moved rigidly so that the first PCA
        centroid is at `first_pose` (x, y, yaw): an external fix, as
        `sasnav navigate --first-pose`."""
        fx, fy, ft = (float(v) for v in first_pose)
        c0 = self.centroids[0]
        dt = ft - c0["theta"]
        cs, sn = math.cos(dt), math.sin(dt)
        out = self.nav.copy()
        for part in ("tx", "array"):
            x = self.nav[part]["x"] - c0["x"]
            y = self.nav[part]["y"] - c0["y"]
            out[part]["x"] = fx + cs * x - sn * y
            out[part]["y"] = fy + sn * x + cs * y
            out[part]["theta"] = self.nav[part]["theta"] + dt
        return out


def _navigation_from_c(nv, truth):
    n = nv.n_pings
    pairs = []
    has_truth = bool(nv.has_truth)
    for j in range(nv.n_pairs):
        pr = nv.pairs[j]
        t = _pose(pr.truth) if has_truth else None
        err = _pose(pr.error) if has_truth else None
        aid = _pose(pr.aiding) if nv.aiding_used else None
        aid_s = _pose(pr.aiding_sigma) if nv.aiding_used else None
        nom = _pose(pr.nominal)
        pairs.append(NavigatedPair(
            pr.p, pr.q, _status_name(pr.status), nom, _pose(pr.fused),
            _verdict_name(pr.verdict), _verdict_name(pr.first_verdict),
            lib().sasnav_resolution_name(pr.resolution).decode(),
            _estimate_from_c(pr.result, pr.p, pr.q, nom, t),
            _estimate_from_c(pr.first_result, pr.p, pr.q, nom, t), t, err, aid, aid_s,
            bool(pr.eta_outlier)))

    def poses(ptr, dtype):
        return _copy_out(_addr(ptr), dtype, n) if (has_truth and ptr) else None

    return Navigation(
        _METHOD_NAMES.get(nv.method, str(nv.method)), n,
        _copy_out(_addr(nv.nav), PING_POSE_DTYPE, n), _copy_out(_addr(nv.centroids), POSE_DTYPE, n),
        nv.track_angle, pairs, nv.n_failed, nv.n_flagged, nv.n_resolved, nv.n_skipped,
        bool(nv.aiding_used), nv.lsq_iterations, has_truth, truth,
        poses(nv.truth_centroids, POSE_DTYPE), poses(nv.anchored, PING_POSE_DTYPE),
        poses(nv.cumulative, POSE_DTYPE), poses(nv.differential, POSE_DTYPE),
        _pose(nv.rms_cumulative) if has_truth else None,
        _pose(nv.rms_differential) if has_truth else None,
        nv.seconds, nv.seconds_per_pair, nv.pairs_per_second, nv.threads_over_pairs,
        "gyro" if nv.gyro_tx_yaw else "pairs" if nv.pairs_tx_yaw else "none",
        nv.eta_median, nv.n_eta_outliers,
        _copy_out(_addr(nv.formal_sigma), POSE_DTYPE, n) if nv.formal_sigma else None)


def _navigate_opts(pair, dpca, opts):
    """sasnav_navigate_opts from the keyword options of navigate()."""
    L = lib()
    no = C.NavigateOpts()
    L.sasnav_navigate_default_opts(ctypes.byref(no))
    opts = dict(opts)
    if "threads" in opts:
        opts["nthreads"] = opts.pop("threads")
    nav_fields = {k for k, _ in C.NavigateOpts._fields_} - _NOT_SETTABLE - {"pair", "dpca"}
    pair_fields = {k for k, _ in C.PairOpts._fields_}
    pair_opts = dict(pair or {})
    for key in list(opts):
        if key not in nav_fields and key in pair_fields:
            pair_opts[key] = opts.pop(key)
    _set_fields(no, opts, "navigate")
    _set_fields(no.pair, pair_opts, "pair")
    if dpca:
        _set_fields(no.dpca, dict(dpca), "dpca")
    if "coarse_k" not in pair_opts:
        no.pair.coarse_k = min(no.pair.coarse_k, no.pair.k)
    if "coarse_i" not in pair_opts:
        no.pair.coarse_i = min(no.pair.coarse_i, no.pair.i)
    return no


def _check_navigable(run):
    if not isinstance(run, (Run, StreamedRun)):
        raise TypeError(f"expected a sasnav.Run or StreamedRun, got {type(run).__name__}")
    if run.n_pings < 2:
        raise ValueError("navigate needs a run of at least two pings")


class PairRecords:
    """First pair estimates of (part of) a navigation, by content key
    (sasnav_pair_record): what navigate_part returns, and what navigate
    takes as `done` (already estimated). Join the parts with
    PairRecords.join([...])."""

    def __init__(self, array):
        self._array = array  # ctypes array of C.PairRecord

    def __len__(self):
        return len(self._array)

    @staticmethod
    def join(parts):
        parts = list(parts)
        n = sum(len(p) for p in parts)
        arr = (C.PairRecord * n)()
        k = 0
        for part in parts:
            for rec in part._array:
                arr[k] = rec
                k += 1
        return PairRecords(arr)

    @property
    def pairs(self):
        """(p, q) of each record, in order."""
        return [(r.p, r.q) for r in self._array]


def navigate_part(run, part, n_parts, *, pair=None, dpca=None, **opts):
    """The first estimates of one part of a navigation spread over
    processes (sasnav_navigate_part: pairs j with j % n_parts == part);
    navigate(run, done=PairRecords.join(parts)) then gives the same
    navigation as one call, bit for bit. Same options as navigate."""
    _check_navigable(run)
    no = _navigate_opts(pair, dpca, opts)
    recs = ctypes.POINTER(C.PairRecord)()
    n = ctypes.c_int(0)
    with _run_arg(run) as r:
        check(lib().sasnav_navigate_part(r, ctypes.byref(no), int(part), int(n_parts), ctypes.byref(recs),
                                         ctypes.byref(n)))
    try:
        arr = (C.PairRecord * n.value)()
        if n.value:
            ctypes.memmove(arr, recs, ctypes.sizeof(C.PairRecord) * n.value)
        return PairRecords(arr)
    finally:
        c_free(ctypes.cast(recs, ctypes.c_void_p).value)


def navigate(run, *, pair=None, dpca=None, progress=None, done=None, **opts):
    """Navigates a run from its ping-pair estimates (as `sasnav navigate`).

    run: a Run, or a StreamedRun (open_run: the pings are read from the
    file as the pairs need them). opts: any field of sasnav_navigate_opts
    (navigate.h) by name: method
    ("subspace", "dpca", "aiding"), long_baselines, align, resolve,
    use_aiding, motion_sigma=(s, w, y), link_sigma, long_sigma, link_eta, eta_weight,
    aiding_gate, eta_outlier (math.inf: off), speed_lags ("none", "dvl" (default), "pairs"), aiding_bias_sigma,
    tx_yaw ("auto" (default), "pairs", "none": a multi-transmitter head's
    turn between transmission and reception, as `--tx-yaw`), threads (= nthreads); any other keyword that names a field of
    sasnav_pair_opts (k, i, yaw_sigma, fix_yaw, ...) goes to the subspace
    estimator, as do the entries of the dict `pair`; `dpca` is a dict of
    sasnav_dpca_opts fields. progress(done, total, p, q, seconds) is called
    before the first pair and after each (from the estimating thread).
    done: PairRecords of pairs estimated already (navigate_part), taken
    instead of estimated. Returns a Navigation."""
    _check_navigable(run)
    L = lib()
    no = _navigate_opts(pair, dpca, opts)
    if done is not None:
        if not isinstance(done, PairRecords):
            raise TypeError(f"done must be PairRecords (navigate_part), got {type(done).__name__}")
        no.done = ctypes.cast(done._array, ctypes.POINTER(C.PairRecord))
        no.n_done = len(done)
    cb = None
    if progress is not None:
        def _cb(pr, user):
            pr = pr.contents
            progress(pr.done, pr.total, pr.p, pr.q, pr.seconds)
        cb = C.PROGRESS_FN(_cb)
        no.progress = cb
    out = C.NavigationC()
    with _run_arg(run) as r:
        check(L.sasnav_navigate(r, ctypes.byref(no), ctypes.byref(out)))
    try:
        truth = None if run.truth is None else ping_poses(run.truth).copy()
        return _navigation_from_c(out, truth)
    finally:
        L.sasnav_navigation_free(ctypes.byref(out))
        del cb


# ---------------------------------------------------------------------------
# Virtual arrays (single-channel sonars)


@dataclass
class VirtualPair:
    """One pair of virtual pings (sasnav_virtual_pair): the groups' first
    pings p and q, the nominal displacement of q's group centroid in p's
    (from the input navigation), the truth (None without one), the
    estimate (PairEstimate; its `displacement` is the estimated step),
    whether the step went into the navigation (`used`: verdict "ok";
    otherwise the input's step was kept) and the step used (Pose)."""

    p: int
    q: int
    nominal: Pose
    truth: Optional[Pose]
    estimate: PairEstimate
    used: bool
    step: Pose


@dataclass(eq=False)
class VirtualNavigation:
    """The result of navigate_virtual() (sasnav_virtual_navigation): the
    estimated ping poses `nav` (PING_POSE_DTYPE), the groups' centroids
    from the input (`centroid_in`) and estimated (`centroid`, POSE_DTYPE
    [n_groups]), the pairs, the layouts' turns (`layout_turn`, rad, with
    align_heading), their mean, rms and exposure (m), the loop's
    misclosure (closed), the steps' length scale (keep_length), the steps
    that kept the input's (`n_fallback`), and which axis came from where
    (`along_track`: "echoes" or "input")."""

    n_pings: int
    k: int
    stride: int
    interleave: int
    closed: bool
    align_heading: bool
    along_track: str
    nav: np.ndarray
    centroid_in: np.ndarray
    centroid: np.ndarray
    pairs: List[VirtualPair]
    layout_turn: np.ndarray
    turn_mean: float
    turn_rms: float
    turn_exposure: float
    misclosure: Optional[Pose]
    length_scale: float
    n_fallback: int
    iterations: int
    seconds: float


def navigate_virtual(run, k=4, *, interleave=1, stride=0, closed=False, iterations=2,
                     keep_length=False, align_heading=False, along_track="echoes",
                     estimate_yaw=False, threads=0, pair=None, **opts):
    """Navigates a run by virtual pings of k pings (as `sasnav navigate
    --virtual-array K`; docs/navigation.md, "Virtual arrays"): every
    interleave-th ping makes a group, a group starts every `stride` pings
    (0: k for interleave 1, else 1); the displacement between consecutive
    groups is estimated and chained; closed: the track closes on itself (a
    turntable); keep_length: the steps scaled to the input's length;
    align_heading: the layouts turned onto the headings; along_track
    "input": the input's along-track kept and the across-track corrected
    from the steps' sway (implies align_heading; excludes estimate_yaw);
    estimate_yaw: each step's yaw estimated (default: the input's). As the
    CLI, the estimator's grid is centred at the run's range of interest,
    0.35 x that range square (cross_extent, range_extent), and its search
    box +-0.7 ping spacings; any other keyword that names a field of
    sasnav_pair_opts, and the entries of the dict `pair`, go to the
    estimator. Returns a VirtualNavigation."""
    _check_navigable(run)
    if along_track not in ("echoes", "input"):
        raise ValueError(f"along_track is 'echoes' or 'input' (got {along_track!r})")
    along = along_track == "input"
    if "fix_yaw" in opts or "fix_yaw" in (pair or {}):
        raise ValueError("navigate_virtual: the yaw is held unless estimate_yaw=True (no fix_yaw)")
    if isinstance(k, bool) or not isinstance(k, int) or k < 2:
        raise ValueError(f"navigate_virtual: k needs 2 or more pings (got {k!r})")
    if along and estimate_yaw:
        raise ValueError("along_track='input' keeps the input's yaws: it excludes estimate_yaw")
    L = lib()
    vo = C.VirtualOpts()
    L.sasnav_virtual_default_opts(ctypes.byref(vo))
    _set_fields(vo, {"k": k, "interleave": interleave, "stride": stride, "closed": bool(closed),
                     "iterations": iterations, "nthreads": threads, "keep_length": bool(keep_length),
                     "align_heading": bool(align_heading) or along, "along_input": along}, "virtual")
    po = vo.pair
    roi = run.range_of_interest
    po.range = roi
    po.cross_extent = po.range_extent = 0.35 * roi
    step = run.ping_spacing if run.ping_spacing > 0 else 0.01
    po.fix_yaw = 0 if estimate_yaw else 1
    po.box = C.Pose(0.7 * step, 0.7 * step, 0.02 if po.fix_yaw else 0.0)
    pair_opts = dict(pair or {})
    pair_opts.update(opts)
    if "threads" in pair_opts or "nthreads" in pair_opts:
        raise ValueError("navigate_virtual: give threads as its own keyword (pairs run one thread each)")
    _set_fields(po, pair_opts, "pair")
    if "coarse_k" not in pair_opts:
        po.coarse_k = po.k
    if "coarse_i" not in pair_opts:
        po.coarse_i = po.i
    out = C.VirtualNavigationC()
    with _run_arg(run) as r:
        check(L.sasnav_navigate_virtual(r, ctypes.byref(vo), ctypes.byref(out)))
    try:
        ng, n = out.n_groups, out.n_pings
        has_truth = run.truth is not None
        pairs = []
        for j in range(out.n_pairs):
            vp = out.pairs[j]
            nom = _pose(vp.nominal)
            t = _pose(vp.truth) if has_truth else None
            # the estimate's truth is the true motion error (true - nominal step)
            terr = None if t is None else Pose(t.x - nom.x, t.y - nom.y, t.theta - nom.theta)
            est = _estimate_from_c(vp.est, vp.first_p, vp.first_q, nom, terr)
            pairs.append(VirtualPair(vp.first_p, vp.first_q, nom, t, est, bool(vp.used), _pose(vp.step)))
        return VirtualNavigation(
            n, out.k, out.stride, out.interleave, bool(out.closed), bool(out.align_heading),
            "input" if out.along_input else "echoes",
            _copy_out(_addr(out.nav), PING_POSE_DTYPE, n),
            _copy_out(_addr(out.centroid_in), POSE_DTYPE, ng),
            _copy_out(_addr(out.centroid), POSE_DTYPE, ng), pairs,
            _copy_out(_addr(out.layout_turn), np.float64, ng), out.turn_mean, out.turn_rms,
            out.turn_exposure, _pose(out.misclosure) if out.closed else None, out.length_scale,
            out.n_fallback, out.iterations, out.seconds)
    finally:
        L.sasnav_virtual_navigation_free(ctypes.byref(out))


# ---------------------------------------------------------------------------
# Imaging


def default_grid(run, nav=None):
    """The grid `sasnav image` uses by default: the track's extent +-0.5 m
    by the range of interest +-0.8 m, at quarter-element (or c / 4B)
    pixels."""
    nav = run.nav if nav is None else ping_poses(nav, run.n_pings)
    c = centroids(nav)
    xmin, xmax = float(c["x"].min()) - 0.5, float(c["x"].max()) + 0.5
    res = run.system.sound_speed / (4.0 * run.system.bandwidth)
    d_rx = run.array.min_rx_length()
    if d_rx > 0 and d_rx / 4.0 < res:
        res = d_rx / 4.0
    r0 = run.range_of_interest if run.range_of_interest > 0 else 10.0
    nx = int(math.ceil((xmax - xmin) / res)) + 1
    ny = int(math.ceil(1.6 / res)) + 1
    return Grid.make(xmin, xmin + (nx - 1) * res, nx, r0 - 0.8, r0 - 0.8 + (ny - 1) * res, ny)


def image(run, grid=None, nav=None, *, ping=None, cgls=0, tikhonov=0.0, threads=0,
          tolerance=None, ffbp=False, ffbp_oversampling=2.0):
    """Backprojects `run` on `grid` (as `sasnav image`).

    ffbp=True: fast factorised backprojection (as `sasnav image --ffbp`:
    the same image up to about -45 dB, faster on long apertures and fine
    grids; docs/survey.md), with polar grids at `ffbp_oversampling` (1.25
    to 4) times Nyquist.

    grid: a Grid, (x_min, x_max, nx, y_min, y_max, ny), or None (the
    default_grid). nav: None (the run's own nav), "truth" (the run's true
    poses), ping poses, or a NavData / Navigation. ping: image that ping
    alone; with cgls=K > 0 its CGLS pseudo-inverse (K iterations, Tikhonov
    weight `tikhonov`) instead of its backprojection. Returns an Image."""
    if not isinstance(run, (Run, StreamedRun)):
        raise TypeError(f"expected a sasnav.Run or StreamedRun, got {type(run).__name__}")
    if isinstance(run, StreamedRun) and ping is not None:
        raise ValueError("ping= images one ping of a Run in memory (read_run), not of a StreamedRun")
    if isinstance(nav, str):
        if nav != "truth":
            raise ValueError(f"nav is None, 'truth', or ping poses (got {nav!r})")
        if run.truth is None:
            raise ValueError("nav='truth': the run holds no ground truth")
        nav = run.truth
    elif nav is not None and hasattr(nav, "nav"):
        nav = nav.nav
    poses = ping_poses(run.nav if nav is None else nav, run.n_pings, "nav")
    g = default_grid(run, poses) if grid is None else _as_grid(grid)
    gc = g._to_c()
    oo = _op_opts(threads, tolerance)
    if cgls and ping is None:
        raise ValueError("cgls needs ping")
    out = np.zeros((g.ny, g.nx), np.complex64)
    L = lib()
    if ffbp:
        if ping is not None:
            raise ValueError("ffbp images whole runs, not ping=")
        fo = C.FfbpOpts(float(ffbp_oversampling))
        with _run_arg(run) as r:
            check(L.sasnav_ffbp_tile(r, _poses_ptr(poses), ctypes.byref(gc), 0, g.nx, 0, g.ny,
                                     ctypes.byref(oo), ctypes.byref(fo), out.ctypes.data, None, None))
        return Image(out, g)
    if ping is None:
        with _run_arg(run) as r:
            check(L.sasnav_backproject(r, _poses_ptr(poses), ctypes.byref(gc), ctypes.byref(oo),
                                       out.ctypes.data))
        return Image(out, g)
    if int(ping) != ping or not 0 <= ping < run.n_pings:
        raise ValueError(f"ping {ping!r} out of range (the run has {run.n_pings} pings)")
    ping = int(ping)
    npx = g.nx * g.ny
    x = np.zeros(npx)
    y = np.zeros(npx)
    dptr = ctypes.POINTER(ctypes.c_double)
    L.sasnav_grid_points(ctypes.byref(gc), C.Pose(0, 0, 0), x.ctypes.data_as(dptr),
                         y.ctypes.data_as(dptr))
    sys_c, arr_c = run.system._to_c(), run.array._to_c()
    win = C.Window(float(run.t0), run.n_samples)
    data = np.ascontiguousarray(run.raw[ping], dtype=np.complex64)
    op = ctypes.c_void_p()
    try:
        check(L.sasnav_op_create(ctypes.byref(sys_c), ctypes.byref(arr_c), ctypes.byref(win), npx,
                                 x.ctypes.data_as(dptr), y.ctypes.data_as(dptr), ctypes.byref(oo),
                                 ctypes.byref(op)))
        off = getattr(run, "channel_offset", None)
        if off is not None:
            off = ping_poses(off, run.n_rx, "run.channel_offset")
        check(L.sasnav_op_set_ping(op, _poses_ptr(poses[ping:ping + 1]),
                                   None if off is None else _poses_ptr(off)))
        if cgls:
            co = C.CglsOpts(int(cgls), float(tikhonov))
            check(L.sasnav_cgls(op, data.ctypes.data, ctypes.byref(co), out.ctypes.data, None))
        else:
            check(L.sasnav_op_adjoint(op, data.ctypes.data, out.ctypes.data))
    finally:
        L.sasnav_op_destroy(op)
    return Image(out, g)
