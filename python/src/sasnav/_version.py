# The package's version: the C library's (checked by tests/test_api.py).
__version__ = "0.1.0"
