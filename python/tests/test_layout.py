"""Guards against drift between the ctypes mirrors (sasnav/_cdefs.py) and
the C headers: a small C program compiled against include/ prints sizeof and
offsetof of every field of every mirrored struct, and the values of the
constants and enums the binding relies on; they must equal what ctypes
computes. Skipped where no C compiler is available."""

import ctypes
import os
import re
import shutil
import subprocess

import pytest

from sasnav import _cdefs as C


def _c_program():
    lines = ["#include <stddef.h>", "#include <stdio.h>"]
    lines += [f'#include "sasnav/{h}"' for h in C.HEADERS]
    lines.append("int main(void)\n{")
    for s in C.STRUCTS:
        t = s._c_name_
        lines.append(f'    printf("{t} %zu\\n", sizeof({t}));')
        for name, _ in s._fields_:
            lines.append(f'    printf("{t}.{name} %zu\\n", offsetof({t}, {name}));')
    for name in C.CONSTANTS:
        lines.append(f'    printf("{name} %d\\n", (int)({name}));')
    lines.append("    return 0;\n}")
    return "\n".join(lines) + "\n"


def _expected():
    out = {}
    for s in C.STRUCTS:
        t = s._c_name_
        out[t] = ctypes.sizeof(s)
        for name, _ in s._fields_:
            out[f"{t}.{name}"] = getattr(s, name).offset
    for name, value in C.CONSTANTS.items():
        out[name] = value
    return out


@pytest.fixture(scope="module")
def c_layout(tmp_path_factory, source_dir):
    cc = shutil.which(os.environ.get("CC", "cc"))
    if not cc:
        pytest.skip("no C compiler")
    d = tmp_path_factory.mktemp("layout")
    src, exe = d / "layout.c", d / "layout"
    src.write_text(_c_program())
    r = subprocess.run([cc, "-std=c11", "-I", str(source_dir / "include"), str(src), "-o", str(exe)],
                       capture_output=True, text=True)
    assert r.returncode == 0, f"cannot compile the layout program:\n{r.stderr}"
    r = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    return {k: int(v) for k, v in (line.split() for line in r.stdout.splitlines())}


def test_struct_layout_matches_headers(c_layout):
    expected = _expected()
    assert c_layout.keys() == expected.keys()
    wrong = [f"{k}: C {c_layout[k]}, ctypes {expected[k]}" for k in expected if c_layout[k] != expected[k]]
    assert not wrong, "ctypes mirrors differ from the headers:\n" + "\n".join(wrong)


def test_bound_functions_are_public(source_dir):
    """Every function the binding calls is a sasnav_ function declared in
    include/sasnav/*.h (the shared libraries export only those)."""
    text = "\n".join(p.read_text() for p in (source_dir / "include" / "sasnav").glob("*.h*"))
    missing = [n for n in C.PROTOTYPES
               if not n.startswith("sasnav_") or not re.search(r"\b%s\s*\(" % n, text)]
    assert not missing, f"not declared in include/sasnav: {missing}"


def test_bound_functions_are_exported():
    from sasnav import _lib
    L = _lib.lib()
    for name in C.PROTOTYPES:
        assert hasattr(L, name), name
