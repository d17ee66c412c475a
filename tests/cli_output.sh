#!/bin/sh
# The CLI's output read, not just its exit status: tests/cli-tests/*.t
# (cram format; runner and format in tests/cli-tests/run.py) hold every
# command's help, its usage errors and typical runtime errors with the
# exact (or patterned) text a user sees. docs/cli.md, "Output tests".
# Usage: sh tests/cli_output.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_output.sh path/to/sasnav}
exec python3 "$(dirname "$0")/cli-tests/run.py" "$CLI"
