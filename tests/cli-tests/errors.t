Runtime failures: exit status 1 and one line on standard error naming the
file and what is wrong with it; no output file left behind. Paths of the
scratch directory are matched by a pattern.

A missing file, a half-copied one, one that is not HDF5:

  $ sasnav image missing.h5 -o img.h5 2>&1
  sasnav image: cannot read missing.h5: cannot open: No such file or directory
  [1]
  $ sasnav navigate truncated.h5 -o n.h5 2>&1
  sasnav navigate: cannot read truncated.h5: corrupt or truncated HDF5 file (HDF5: truncated file: *) (glob)
  [1]
  $ sasnav pair table.csv 2>&1
  sasnav pair: cannot read table.csv: not an HDF5 file
  [1]
  $ ls n.h5 img.h5 2>&1
  ls: cannot access 'n.h5': No such file or directory
  ls: cannot access 'img.h5': No such file or directory
  [2]

A navigation file where a run is expected:

  $ sasnav image nav.h5 -o img.h5 2>&1
  sasnav image: cannot read nav.h5: root attribute 'format' is "sasnav-nav", expected "sasnav-run"
  [1]

Configs with an unknown key or an impossible value:

  $ sasnav simulate --preset point --config bad.yaml -o x.h5 2>&1
  sasnav simulate: invalid configuration: bad.yaml:2: scene.targets[0]: expected [x, y, amplitude]
  [1]
  $ sasnav simulate --preset point --config negative.yaml -o x.h5 2>&1
  sasnav simulate: invalid configuration: negative.yaml:2: system.sound_speed: must be > 0, got -1500
  [1]
  $ sasnav simulate --preset point --config missing.yaml -o x.h5 2>&1
  sasnav simulate: invalid configuration: missing.yaml: cannot open: No such file or directory
  [1]

An output that cannot be written (a file where the directory should be):

  $ sasnav simulate --preset point -o blocker/run.h5 2>&1
  sasnav simulate: cannot write blocker/run.h5: cannot create a temporary file next to it: Not a directory
  [1]
  $ sasnav image run.h5 -o blocker/img.h5 2>&1
  sasnav image: cannot write blocker/img.h5: cannot create a temporary file next to it: Not a directory
  [1]

Ping indices outside the run:

  $ sasnav pair run.h5 --p 0 --q 99 2>&1
  sasnav pair: --q 99: run.h5 has 17 pings (0..16)
  [1]

Recording directories without recordings:

  $ sasnav ingest --wav emptydir -o x.h5 2>&1
  sasnav ingest: cannot ingest the WAV recording emptydir: emptydir/positions.csv: cannot open: No such file or directory
  [1]
  $ sasnav ingest --airsas emptydir -o x.h5 2>&1
  sasnav ingest: cannot read the AirSAS recording emptydir: emptydir/Coordinates.csv: cannot open: No such file or directory
  [1]

Checkpoints that are not this command's:

  $ sasnav navigate run.h5 --method dpca --checkpoint foreign.ckpt -o n.h5 2>&1
  sasnav navigate: cannot use checkpoint foreign.ckpt: foreign.ckpt is not a sasnav checkpoint (give another --checkpoint file, or remove it)
  [1]
  $ sasnav navigate run.h5 --method dpca --checkpoint table.csv -o n.h5 2>&1
  sasnav navigate: cannot use checkpoint table.csv: table.csv is not a sasnav checkpoint (give another --checkpoint file, or remove it)
  [1]
