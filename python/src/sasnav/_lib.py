"""Loading the shared library, errors, and the HDF5 lock."""

import ctypes
import ctypes.util
import os
import threading

from . import _cdefs

# The library's soname: libsasnav (the I/O layer) links libsasnav_core, and
# symbols of both are reached through its handle (dlsym searches the
# dependencies of the object it is given).
SONAME = "libsasnav.so.0"

_lock = threading.Lock()
_lib = None
_libc = None

# HDF5 is a serial build: no two I/O calls may run at once (io.h).
io_lock = threading.RLock()


class Error(Exception):
    """A sasnav C call returned a non-zero status.

    str(error) is the library's message (sasnav_last_error()); ``code`` is
    the status (a negative SASNAV_ERR_* value) and ``name`` its short
    description (sasnav_strerror())."""

    def __init__(self, code, message, name=""):
        super().__init__(message)
        self.code = code
        self.message = message
        self.name = name


def _candidates():
    explicit = os.environ.get("SASNAV_LIBRARY")
    if explicit:
        return [explicit]
    names = [SONAME, "libsasnav.so"]
    found = ctypes.util.find_library("sasnav")
    if found and found not in names:
        names.append(found)
    return names


def lib():
    """The loaded library (loaded once, with the prototypes declared)."""
    global _lib, _libc
    if _lib is not None:
        return _lib
    with _lock:
        if _lib is not None:
            return _lib
        errors = []
        for name in _candidates():
            try:
                handle = ctypes.CDLL(name)
            except OSError as e:
                errors.append(f"{name}: {e}")
                continue
            _cdefs.declare(handle)
            # The library allocates the buffers of sasnav_image_read and
            # sasnav_nav_read with malloc and documents free() to release
            # them: the C library's free, reached through the process.
            libc = ctypes.CDLL(None)
            libc.free.restype = None
            libc.free.argtypes = [ctypes.c_void_p]
            _libc = libc
            _lib = handle
            return _lib
        raise OSError(
            "cannot load the sasnav shared library (set LD_LIBRARY_PATH to the "
            "folder holding libsasnav.so.0, or SASNAV_LIBRARY to its path): "
            + "; ".join(errors))


def c_free(address):
    """free() for the buffers the library documents as malloc'ed."""
    if address:
        lib()
        _libc.free(address)


def check(rc):
    """Raises Error with the library's message when rc != 0."""
    if rc != 0:
        raise error(rc)
    return rc


def error(rc):
    L = lib()
    msg = L.sasnav_last_error()
    name = L.sasnav_strerror(rc)
    name = name.decode("utf-8", "replace") if name else ""
    msg = msg.decode("utf-8", "replace") if msg else ""
    return Error(rc, msg or name or f"sasnav error {rc}", name)


def path_arg(path):
    """A file name for the C library (bytes, file-system encoding)."""
    p = os.fsencode(os.fspath(path))
    if b"\0" in p:
        raise ValueError("a path may not contain NUL characters")
    return p
