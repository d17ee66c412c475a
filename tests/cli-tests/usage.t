Usage errors: one line on standard error naming the command, ending with
a pointer to its help, exit status 2, nothing on standard output.

  $ sasnav
  [2]
  $ sasnav 2>&1 | head -n 1
  usage: sasnav COMMAND [options]
  $ sasnav navgate 2>&1
  sasnav: unknown command 'navgate' (did you mean 'navigate'?)
  run 'sasnav --help' for the commands
  [2]
  $ sasnav frobnicate 2>&1
  sasnav: unknown command 'frobnicate'
  run 'sasnav --help' for the commands
  [2]
  $ sasnav simulate 2>&1
  sasnav simulate: an output file is required (-o run.h5) (see 'sasnav simulate --help')
  [2]
  $ sasnav simulate --preset nope -o x.h5 2>&1
  sasnav simulate: --preset needs paper-pair, paper-trajectory, point or tank (got 'nope') (see 'sasnav simulate --help')
  [2]
  $ sasnav simulate --preset point --snr loud -o x.h5 2>&1
  sasnav simulate: --snr needs a number or 'inf' (see 'sasnav simulate --help')
  [2]
  $ sasnav simulate -q 2>&1
  sasnav simulate: unknown option '-q' (see 'sasnav simulate --help')
  [2]
  $ sasnav image 2>&1
  sasnav image: exactly one input run file is required (see 'sasnav image --help')
  [2]
  $ sasnav image run.h5 --treads 2 -o y.h5 2>&1
  sasnav image: unknown option '--treads' (did you mean '--threads'?) (see 'sasnav image --help')
  [2]
  $ sasnav image run.h5 --nav nav.h5 --truth -o y.h5 2>&1
  sasnav image: --nav and --truth exclude each other (see 'sasnav image --help')
  [2]
  $ sasnav pair 2>&1
  sasnav pair: exactly one input run file is required (see 'sasnav pair --help')
  [2]
  $ sasnav pair run.h5 --threads 2>&1
  sasnav pair: option '--threads' needs a value (see 'sasnav pair --help')
  [2]
  $ sasnav pair run.h5 --p 1 --q 1 2>&1
  sasnav pair: --p and --q name the same ping (1) (see 'sasnav pair --help')
  [2]
  $ sasnav cuts run.h5 2>&1
  sasnav cuts: an output directory is required (-o DIR) (see 'sasnav cuts --help')
  [2]
  $ sasnav ingest -o x.h5 2>&1
  sasnav ingest: an input is required (--airsas DIR or --wav DIR) (see 'sasnav ingest --help')
  [2]
  $ sasnav tank 2>&1
  sasnav tank: an output directory is required (-o DIR) (see 'sasnav tank --help')
  [2]
  $ sasnav navigate run.h5 2>&1
  sasnav navigate: an output file is required (-o nav.h5) (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate run.h5 --outptu y 2>&1
  sasnav navigate: unknown option '--outptu' (did you mean '--output'?) (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate run.h5 --method foo -o y.h5 2>&1
  sasnav navigate: --method needs subspace, dpca or aiding (got 'foo') (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate run.h5 --fix-yaw --yaw-sigma 1e-3 -o y.h5 2>&1
  sasnav navigate: estimator options: fix_yaw and yaw_sigma > 0 exclude each other (a held yaw has no prior) (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate run.h5 --k 0 -o y.h5 2>&1
  sasnav navigate: --k needs 1..100 (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate run.h5 --first-pose 1,2 -o y.h5 2>&1
  sasnav navigate: --first-pose needs X,Y,YAW (see 'sasnav navigate --help')
  [2]
  $ sasnav navigate a.h5 b.h5 -o y.h5 2>&1
  sasnav navigate: exactly one input run file is required (see 'sasnav navigate --help')
  [2]
  $ sasnav refine -o x.h5 2>&1
  sasnav refine: a run file and a navigation file are required (see 'sasnav refine --help')
  [2]
  $ sasnav demo --threads many 2>&1
  sasnav demo: --threads needs an integer 0..1024 (see 'sasnav demo --help')
  [2]
  $ sasnav validate run.h5 2>&1
  sasnav validate: an output directory is required (-o DIR) (see 'sasnav validate --help')
  [2]
  $ sasnav validate run.h5 --k-min 0 -o v 2>&1
  sasnav validate: --k-min needs 1..127 (see 'sasnav validate --help')
  [2]
  $ sasnav navigate run.h5 --checkpoint n.h5 -o n.h5 2>&1
  sasnav navigate: --checkpoint and -o name the same file (n.h5) (see 'sasnav navigate --help')
  [2]
  $ sasnav refine run.h5 nav.h5 --checkpoint ./nav.h5 -o nav.h5 2>&1
  sasnav refine: --checkpoint and -o name the same file (nav.h5) (see 'sasnav refine --help')
  [2]
  $ sasnav refine run.h5 nav.h5 --window 2 -o x.h5 2>&1
  sasnav refine: --window needs 0 (the whole run) or a number of pings >= 3 (see 'sasnav refine --help')
  [2]
  $ sasnav refine run.h5 nav.h5 --window 8 --checkpoint c.h5 -o x.h5 2>&1
  sasnav refine: --checkpoint works on runs of one window: run.h5 has 17 pings, --window is 8 (use --window 0 to refine it whole) (see 'sasnav refine --help')
  [2]
  $ sasnav navigate run.h5 --checkpoint ./new.h5 -o emptydir/../new.h5 2>&1
  sasnav navigate: --checkpoint and -o name the same file (emptydir/../new.h5) (see 'sasnav navigate --help')
  [2]
