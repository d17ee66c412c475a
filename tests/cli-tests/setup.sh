#!/bin/sh
# Fixtures of the CLI output tests (run.py runs this in the scratch
# directory, with sasnav on PATH): a small valid run, its navigation, and
# broken files of the kinds users feed in.
set -eu
sasnav simulate --preset point --aiding -o run.h5 2> /dev/null
sasnav navigate run.h5 --method aiding -o nav.h5 > /dev/null 2>&1 # dead reckoning: instant
head -c 2048 run.h5 > truncated.h5                  # a half-copied file
printf 'time,x,y\n0,1,2\n' > table.csv              # not HDF5 at all
printf 'not a checkpoint\n' > foreign.ckpt
printf 'scene:\n  targets: [[0, 10, 1, 0]]\n  wrong_key: 3\n' > bad.yaml
printf 'system:\n  sound_speed: -1500\n' > negative.yaml
mkdir -p emptydir
: > blocker                                          # a file where a directory is needed
