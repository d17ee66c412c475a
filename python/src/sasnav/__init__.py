"""sasnav: synthetic aperture sonar micronavigation and imaging (Python).

A ctypes binding of the sasnav shared library (libsasnav.so.0, which links
libsasnav_core.so.0), found by the dynamic loader's usual search
(LD_LIBRARY_PATH, the ld.so cache) or at the path in the environment
variable SASNAV_LIBRARY. Tutorial: docs/python.md.

Runs, navigation files and images are read into numpy arrays owned by
Python; every failure of a C call raises sasnav.Error with the library's
message.
"""

from ._version import __version__
from ._lib import Error
from ._core import (
    PING_POSE_DTYPE,
    POSE_DTYPE,
    Aiding,
    Candidate,
    Grid,
    Image,
    NavData,
    NavigatedPair,
    Navigation,
    PairEstimate,
    PairRecords,
    Pose,
    Run,
    StreamedRun,
    Scenario,
    VirtualNavigation,
    VirtualPair,
    SensorArray,
    System,
    centroids,
    default_grid,
    estimate_pair,
    image,
    library_version,
    navigate,
    navigate_part,
    navigate_virtual,
    open_run,
    ping_poses,
    read_image,
    read_nav,
    read_run,
    scenario,
    simulate,
    write_image,
    write_nav,
    write_run,
)

__all__ = [
    "__version__", "Error", "POSE_DTYPE", "PING_POSE_DTYPE", "Aiding", "Candidate", "Grid",
    "Image", "NavData", "NavigatedPair", "Navigation", "PairEstimate", "PairRecords", "Pose",
    "Run", "StreamedRun", "navigate_part", "open_run",
    "Scenario", "SensorArray", "System", "centroids", "default_grid", "estimate_pair", "image",
    "library_version", "navigate", "ping_poses", "read_image", "read_nav", "read_run",
    "scenario", "simulate", "write_image", "write_nav", "write_run",
    "VirtualNavigation", "VirtualPair", "navigate_virtual",
]
