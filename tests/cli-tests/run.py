#!/usr/bin/env python3
"""Runs the CLI output tests in tests/cli-tests/*.t (docs/cli.md, "Output
tests"): the cram format (Mercurial's), as zstd's tests/cli-tests compare
a command's output with what is expected.

A .t file holds prose (ignored) and commands. A command is a line
"  $ COMMAND" (two spaces); its expected output follows as lines indented
by two spaces, then optionally "  [N]" for a non-zero exit status (absent:
0 is expected). COMMAND runs in `sh -c` in a scratch directory prepared by
setup.sh (sasnav on PATH as `sasnav`; its fixtures there), with its
standard error merged into its output only where it says `2>&1`. An
expected line is compared exactly, or, ending in " (glob)", as a
shell-style pattern (`*` any text, `?` one character; `\\*` a star), or,
ending in " (re)", as a Python regular expression matched in full.

Usage: run.py SASNAV [--update] [TEST.t ...]
  --update  rewrites the expected output of every command in place with
            what it printed (exact lines; review the diff before
            committing: the expected text must be what a user should see)
Exit status 0 when every command matched, 1 otherwise (a diff per
mismatch), 2 for a usage error.
"""
import fnmatch
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def parse(path):
    """[(line_index_of_command, command, [expected lines], status,
    end_line_index)] and the file's lines."""
    lines = open(path, encoding="utf-8").read().split("\n")
    cases, i = [], 0
    while i < len(lines):
        if lines[i].startswith("  $ "):
            start, cmd = i, lines[i][4:]
            i += 1
            while i < len(lines) and lines[i].startswith("  > "):  # continuation
                cmd += "\n" + lines[i][4:]
                i += 1
            expected, status = [], 0
            while i < len(lines) and lines[i].startswith("  ") and not lines[i].startswith("  $ "):
                m = re.fullmatch(r"  \[(\d+)\]", lines[i])
                if m:
                    status = int(m.group(1))
                    i += 1
                    break
                expected.append(lines[i][2:])
                i += 1
            cases.append((start, cmd, expected, status, i))
        else:
            i += 1
    return cases, lines


def line_matches(want, got):
    if want.endswith(" (glob)"):
        pat = want[: -len(" (glob)")]
        # fnmatch's [ ] classes would make brackets in messages special
        rx = "".join(".*" if c == "*" else "." if c == "?" else re.escape(c) for c in pat)
        return re.fullmatch(rx, got) is not None
    if want.endswith(" (re)"):
        return re.fullmatch(want[: -len(" (re)")], got) is not None
    return want == got


def run_case(cmd, workdir, env):
    p = subprocess.run(["sh", "-c", cmd], cwd=workdir, env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.DEVNULL, timeout=600)
    out = p.stdout.decode("utf-8", "replace")
    got = out.split("\n")
    if got and got[-1] == "":
        got.pop()
    return got, p.returncode


def main(argv):
    args = [a for a in argv[1:] if a != "--update"]
    update = "--update" in argv[1:]
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    sasnav = os.path.abspath(args[0])
    tests = args[1:] or sorted(os.path.join(HERE, f) for f in os.listdir(HERE) if f.endswith(".t"))
    work = tempfile.mkdtemp(prefix="sasnav-cli-tests-")
    try:
        bindir = os.path.join(work, "bin")
        os.mkdir(bindir)
        os.symlink(sasnav, os.path.join(bindir, "sasnav"))
        env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""), LC_ALL="C",
                   OMP_NUM_THREADS="1", TERM="dumb")
        fixtures = os.path.join(work, "w")
        os.mkdir(fixtures)
        s = subprocess.run(["sh", os.path.join(HERE, "setup.sh")], cwd=fixtures, env=env)
        if s.returncode != 0:
            print("cli-tests: setup.sh failed", file=sys.stderr)
            return 1
        failed = total = 0
        for t in tests:
            cases, lines = parse(t)
            new_lines, last = [], 0
            for start, cmd, expected, status, end in cases:
                total += 1
                got, rc = run_case(cmd, fixtures, env)
                ok = rc == status and len(got) == len(expected) and all(
                    line_matches(w, g) for w, g in zip(expected, got))
                if not ok:
                    failed += 1
                    print(f"FAIL {os.path.basename(t)}:{start + 1}: $ {cmd}")
                    if rc != status:
                        print(f"  exit status {rc}, expected {status}")
                    n = max(len(got), len(expected))
                    for k in range(n):
                        w = expected[k] if k < len(expected) else None
                        g = got[k] if k < len(got) else None
                        if w is None or g is None or not line_matches(w, g):
                            print(f"  line {k + 1}: expected {w!r}\n          got      {g!r}")
                            break
                if update:
                    new_lines += lines[last:start + 1 + cmd.count("\n")]
                    # keep the expected lines that match (globs, regexes)
                    new_lines += ["  " + (expected[k] if k < len(expected) and line_matches(expected[k], g) else g)
                                  for k, g in enumerate(got)]
                    if rc != 0:
                        new_lines.append(f"  [{rc}]")
                    last = end
            if update:
                new_lines += lines[last:]
                with open(t, "w", encoding="utf-8") as f:
                    f.write("\n".join(new_lines))
        print(f"cli-tests: {total - failed} of {total} commands as expected" + (" (updated)" if update else ""))
        return 0 if failed == 0 or update else 1
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
