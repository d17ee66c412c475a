The tool's and every command's help, compared exactly: a change of wording
must be deliberate (`run.py SASNAV --update help.t`, then review the diff).

  $ sasnav --version
  sasnav \d+\.\d+\.\d+ (re)

  $ sasnav --help
  usage: sasnav COMMAND [options]
  
  Synthetic aperture sonar micronavigation (Caporale & Petillot subspace
  intersection) and imaging.
  
  commands:
    simulate   simulate a run (presets paper-pair, paper-trajectory, point)
    image      backproject a run into an image (HDF5 and PNG)
    pair       estimate the motion error between two pings
    cuts       error-function cuts and maps around a point (CSV + PNG)
    ingest     real recordings (AirSAS, WAV) to a run: pulse compression, baseband
    tank       simulate the paper's tank experiment as passband WAV recordings
    navigate   estimate the trajectory of a whole run (subspace or DPCA)
    refine     refine a navigation with all pings together (data-domain fit)
    demo       paper-trajectory end to end: navigation, images, report
    validate   the tank experiment's validation (K sub-sampled runs, SISO/SIMO)
  
  options:
    --help     this text
    --version  the version of sasnav
  
  Run 'sasnav COMMAND --help' for the options of a command. Every command
  that computes takes --threads N. Exit status: 0 success, 1 a failure
  (missing or corrupt input, a computation or a write that failed), 2 a
  usage error (unknown or malformed option, missing argument).

  $ sasnav simulate --help
  usage: sasnav simulate --preset NAME [--config FILE] [--seed N] [--snr DB]
                         [--error SURGE,SWAY,YAW] [--aiding] [--threads N] -o run.h5
         sasnav simulate --preset tank [--seed N] [--omni] -o DIR
  
  Simulates baseband pulse-compressed echoes of a scenario from scatterers
  placed off any image grid, with the true sensor poses, and writes them with
  the nominal and true navigation (docs/format.md).
  
    --preset NAME    paper-pair | paper-trajectory | point | survey | circular
                     (default paper-trajectory; survey: a 300 kHz survey
                     SAS over a 100 m varied seabed; circular: a simulated
                     AirSAS, one channel on a 0.85 m circle; docs/config.md),
                     or tank: the
                     tank experiment as the recordings a user would have
                     (multichannel passband WAV per ping, chirp, positions;
                     'sasnav tank --help'), written into the directory -o DIR
    --config FILE    YAML scenario overriding the preset (docs/config.md)
    --seed N         seed of the scene, trajectory and noise draws
    --snr DB         signal-to-noise ratio in dB ('inf' = noise-free)
    --error S,W,Y    motion error of ping 2 relative to ping 1: surge (m),
                     sway (m), yaw (rad)
    --aiding         also write gyro and DVL measurements of the true
                     trajectory (navigation-grade INS and 600 kHz DVL error
                     models; the config's 'aiding' section sets them;
                     docs/config.md), which 'sasnav navigate' fuses
    --threads N      OpenMP threads (default: all cores)
    -o FILE          output run file (HDF5)
  
  The run is written ping by ping (memory: the scene and one ping).
  'mpirun -np N sasnav simulate ...' spreads the pings over N processes;
  rank 0 writes the same file as one process, bit for bit (docs/survey.md).

  $ sasnav image --help
  usage: sasnav image run.h5 [--nav nav.h5 | --truth] [--grid X0,X1,NX,Y0,Y1,NY]
                      [--png image.png] [--dynamic-range DB] [--threads N]
                      [--ping P [--cgls K] [--tikhonov L]]
                      [--ffbp [--ffbp-oversampling S]] -o image.h5
  
  Backprojects every ping of the run (sum of adjoint ping operators) on a
  grid and writes the complex image (docs/format.md) and optionally a PNG in dB.
  
    --nav FILE        navigation to image with (default: the run's own /nav)
    --truth           image with the run's ground-truth poses (simulations)
    --grid ...        along-track x0,x1,nx and range y0,y1,ny (m); default: the
                      track extent +-0.5 m by the range of interest +-0.8 m at
                      quarter-element pixels
    --png FILE        also write |image| in dB with axes and a colour bar
    --dynamic-range DB  colour scale depth (default 40)
    --threads N       OpenMP threads (default: all cores)
    --ping P          image ping P alone (0-based)
    --cgls K          with --ping: the regularised pseudo-inverse of the ping
                      by K CGLS iterations instead of its backprojection
    --tikhonov L      Tikhonov weight of the CGLS inverse (default 0)
    --ffbp            fast factorised backprojection: subapertures on polar
                      grids merged two by two (faster on long apertures; the
                      error against direct backprojection: docs/survey.md)
    --ffbp-oversampling S  polar grids' sampling over Nyquist (default 2;
                      1.25..4: higher is more exact and slower)
    -o FILE           output image file (HDF5)
  
  Any grid size: the backprojection runs in tiles of rows (about 180 MB of
  operator each), the run read ping by ping. 'mpirun -np N sasnav image ...'
  gives each process a band of rows; rank 0 writes the same image as one
  process, bit for bit (docs/survey.md).

  $ sasnav pair --help
  usage: sasnav pair run.h5 [--p I --q J] [--json] [--k K] [--i I]
                     [--prior S,W,Y] [--yaw-sigma S | --fix-yaw] [--surge-sigma S]
                     [--cross-extent M] [--range-extent M]
                     [--no-global] [--search-grid G] [--subintervals N]
                     [--eta-max E] [--coincidence F] [--compact-contrast C]
                     [--final C] [--equalise M]
                     [--range R] [--lag-model fixed|motion] [--threads N] [--gpu]
  
  Estimates the motion error (displacement minus nominal) of ping q relative
  to ping p: surge and sway in metres, yaw in radians. Without --p/--q the
  first two pings are used. Where the file holds ground truth, prints the
  true values and the errors.
  
  A single pair's verdict lacks the run's checks: `sasnav navigate` also
  flags a pair whose eta stands far above its run's (a bright feature just
  under the compact gate can pull an estimate that passes here as 'ok':
  docs/navigation.md, "On scenarios drawn at random").
  
    --p I, --q J      ping indices (0-based)
    --json            machine-readable output
    --k K, --i I      CGLS and alternating-projection iterations of the
                      final stage (default 8, 8; the paper's 5, 5 are 1.5x
                      faster, with larger surge errors: docs/estimator.md)
    --prior S,W,Y     prior motion error (default 0,0,0)
    --surge-sigma S   scale of a prior on the surge error (m; the nominal
                      step's accuracy, e.g. a plotter's; default none): ranks
                      the global stage's candidates one phase-centre spacing
                      apart, which look alike on compact scenes at a squint
    --no-global       skip the global stage (local search from the prior)
    --search-grid G   grid of the search stages before the final one: auto
                      (default: coarse on a speckle-like scene, fine on a
                      few bright reflectors), fine (full pixels) or coarse
                      (the global stage's; 1.25x faster on seabed pairs;
                      docs/estimator.md)
    --box S,W,Y       half-widths of the search box around the prior (m, m,
                      rad; default 0.06, 0.035 and the grating-lobe-safe yaw)
    --range R         centre range of the estimation grid (default: the run's
                      range of interest)
    --range-extent M  range extent of the estimation grid (m, default 1.6;
                      split between the sub-intervals)
    --subintervals N  split the swath into N range sub-intervals, each with
                      its own EPCA offset and estimate (paper III-B)
    --lag-model M     Tx-array offset per sub-interval: 'fixed' (the run's
                      tx_lag, default) or 'motion' (speed x 2 R / c at the
                      sub-interval's centre range R)
    --final C         the final stage's criterion: 'auto' (default: the joint
                      misfit when the pings' relative yaw is small, the
                      scene speckle-like and the grid covers half the beam's
                      footprint, eta otherwise),
                      'eta' (the paper's) or 'joint' (one scene explains
                      both pings; docs/estimator.md, "A joint-misfit final
                      stage")
    --eta-max E       final eta above which the verdict is 'failed' (default
                      0.6, calibrated at 10 m; correct survey-class pairs at
                      70 m reach 0.6, slipped ones ~0.95: docs/estimator.md,
                      "A survey-class system")
    --coincidence F   on compact scenes, an estimate within F phase-centre
                      spacings of a phase-centre coincidence is 'ambiguous'
                      (its surge is not resolved there; default 0.5: all, 0 off;
                      compact scenes also need an eta margin of 1.25 for
                      'ok': docs/estimator.md, "Verdict")
    --compact-contrast C  the intensity contrast of p's image or of q's above
                      which the scene is compact for the verdict (default 4;
                      speckle about 1, simulated seabeds up to 3.9; 'inf':
                      never; reported as 'contrast', 'contrast_q' in --json)
    --equalise M      on a scene speckle-like at the prior where a feature
                      stands out (its intensity smoothed over 5 cm peaks 9 dB
                      over the mean),
                      the search weights each pixel by the inverse square root
                      of the images' intensity smoothed over M metres, so that
                      a feature far brighter than the seabed does not lead it
                      astray; the final stage and the verdict's eta stay
                      unweighted
                      (default 0.05, at most 0.25; 0: off; 'equalised' and the
                      gate's 'equalise_peak' in --json;
                      docs/estimator.md, "An equalised search")
    --threads N       OpenMP threads
    --gpu             the error evaluations on a CUDA GPU (builds configured
                      with -DSASNAV_CUDA=ON; the same estimates to float
                      rounding: docs/estimator.md, "GPU")

  $ sasnav cuts --help
  usage: sasnav cuts run.h5 [--p I --q J] [--around S,W,Y | --around-truth]
                     [--span S,W,Y] [--n N] [--k K] [--i I] -o DIR
         sasnav cuts --maps [--preset NAME] [--n N] [--k K] [--i I] -o DIR
  
  1-D cuts of zeta and eta along surge, sway and yaw around a motion error
  (default: the ground truth when known, else 0), written as DIR/cut_AXIS.csv
  and DIR/cut_AXIS.png; with --maps, 2-D maps of zeta and eta over the true
  error (simulated pairs of the preset, one axis at a time) and the
  hypothesised error: DIR/map_AXIS_{zeta,eta}.csv and .png.
  
    --span S,W,Y   half-widths of the cuts (default 0.05 m, 0.01 m, 0.05 rad)
    --n N          points per cut (default 81; maps default 21)
    --k K, --i I   iterations (default 8, 8; maps default 2, 1)

  $ sasnav ingest --help
  usage: sasnav ingest --airsas DIR [--background DIR] [options] -o run.h5
  
  Reads an AirSAS circular SAS recording (Flight-*.csv, Coordinates.csv,
  SysParams.csv, WaveformParams.csv), subtracts the empty-scene recording,
  removes the mean room response, pulse-compresses with the recorded LFM,
  demodulates to baseband and writes a run (docs/format.md) with the
  nominal circular navigation; image it with
    sasnav image run.h5 --grid -0.3,0.3,400,-0.3,0.3,400 -o img.h5 --png img.png
  
    --airsas DIR        recording directory
    --wav DIR           tank-style recordings: ping_NNN.wav (multichannel,
                        passband), chirp.wav, positions.csv [, truth.csv,
                        array.csv] (as written by 'sasnav simulate --preset
                        tank'); decimation default 33
    --range R           (--wav) range of interest: centre of the estimation
                        and image grids (m, default 1.5, the tank's plate)
    --background DIR    empty-scene recording, subtracted ping by ping
    --mic N             microphone (column) 1 or 2, or both: one ping of two
                        channels, each at its microphone's height (default 1)
    --first N           first ping, 0-based (default 0)
    --stride K          keep every K-th ping (default 1)
    --pings N           keep at most N pings (default: all)
    --decimation D      baseband decimation of the records (default 4: 25 kHz)
    --matched           plain matched filter instead of compression to the
                        model pulse (flat spectrum over the band)
    --taper T           pulse spectrum taper: none, hann, hamming (default none)
    --f0 HZ             carrier (default: centre of the chirp sweep)
    --bandwidth HZ      band (default: the chirp sweep width)
    --no-room           keep the mean room response
    --radius M          sensor circle radius (default 0.85)
    --clip-run N        refuse records with N equal samples at their extreme
                        value (default 3; 0: no check)
    --threads N         OpenMP threads (default: all cores)
    -o FILE             output run file (HDF5)

  $ sasnav tank --help
  usage: sasnav tank -o DIR [--seed N] [--omni] [--clutter STD] [--plate-range R]
                    [--noise STD]
  
  Simulates the tank experiment of SPEC 4 (8 Rx of 5 cm spaced 5 cm, Tx at
  the array midpoint, 32 pings at 2.5 cm steps with stepping errors, a surge
  jump between pings 11 and 12 and a constant yaw of 1.27e-2 rad; 4 point
  reflectors and weak clutter on a plate 1.5 m away; LFM 90-120 kHz, 3 ms,
  c = 1480 m/s) and writes what the experiment records:
    DIR/ping_000.wav ..  8-channel 32-bit float WAV at 1 MHz (real passband,
                         sample 0 at transmission)
    DIR/chirp.wav        the transmitted chirp (mono)
    DIR/positions.csv    ping,x,y,yaw: nominal plotter positions
    DIR/truth.csv        ping,x,y,yaw: true poses
    DIR/array.csv        rx_spacing,element_length,directivity (read by ingest)
  Turn it into a run with
    sasnav ingest --wav DIR -o run.h5
  
    --seed N    seed of the stepping errors, clutter and noise (default 1)
    --omni      omnidirectional elements (default: the 5 cm elements'
                line-aperture patterns at 105 kHz)
    --clutter STD      amplitude std of the plate's 200 point scatterers
                       (its texture; default 0.02 against reflectors of 1)
    --plate-range R    range of the plate centre (m, default 1.5); the
                       reflectors keep their place on the plate
    --noise STD        white noise std per passband sample (default 1e-3)
    --threads N OpenMP threads (default: all cores)
    -o DIR      output directory (created if missing)

  $ sasnav navigate --help
  usage: sasnav navigate run.h5 [--method subspace|dpca|aiding] [--long-baselines]
                         [--k K] [--i I] [--yaw-sigma S | --fix-yaw] [--surge-sigma S]
                         [--cross-extent M] [--range-extent M] [--eta-max E] [--final C]
                         [--search-grid G] [--coincidence F] [--compact-contrast C]
                         [--eta-outlier R] [--equalise M] [--no-aiding] [--no-resolve]
                         [--motion-sigma S,W,Y] [--speed-lags none|dvl|pairs]
                         [--aiding-bias S,W,Y] [--link-sigma S,W,Y] [--link-eta E]
                         [--threads N] [--gpu] [--json] [--checkpoint FILE]
                         [--first-pose X,Y,YAW | --anchor-truth] -o nav.h5
         sasnav navigate run.h5 --virtual-array K [--interleave M] [--stride S]
                         [--iterations N] [--closed] [--keep-length] [--align-heading]
                         [--along-track echoes|input] [--estimate-yaw] [--k K] [--i I]
                         [--cross-extent M] [--range-extent M] [--threads N] [--json]
                         -o nav.h5
  
  Estimates the displacement of every consecutive ping pair, composes them
  into a trajectory starting at the run's nominal first ping, aligns it to
  the nominal track (the removed track angle is reported) and writes the
  estimated navigation (docs/format.md; with the run's ground truth when it
  has one). Where the run holds the truth, prints the per-pair errors and
  the cumulative errors of the trajectory (the true trajectory moved
  rigidly onto the estimated first ping: the first pose is not observable).
  
  Every pair gets a verdict (ok, ambiguous, failed, no_overlap; one warning
  line on stderr for each pair that is not ok; DPCA's estimates are
  'unchecked', one line for them all). The pairs are then resolved
  jointly over the run: a choice among each pair's candidates with a motion
  model of the vehicle and the run's aiding measurements (gyro, DVL: written
  by 'sasnav simulate --aiding' or by the user, docs/format.md), new estimates
  where a pair failed or disagrees with the aiding, and a robust smoother
  fusing estimates, aiding and motion model (docs/navigation.md). A pair
  without a usable estimate is bridged by the aiding and the motion model
  and reported; the exit status stays 0.
  
    --method M        subspace (default; subspace intersection), dpca, or
                      aiding (the run's gyro and DVL alone: dead reckoning)
    --long-baselines  also estimate pairs (p, p+2) and combine all by least
                      squares (skipped where they share < 2 phase centres)
    --k K, --i I      CGLS and alternating-projection iterations of the
                      subspace estimator's final stage (default: the
                      estimator's, see 'sasnav pair --help')
    --yaw-sigma S     prior on each pair's yaw error, rad (gyro or rail;
                      default none): resolves the surge-yaw ambiguity of
                      compact scenes (see 'sasnav pair --help')
    --surge-sigma S   scale of a prior on each pair's surge error, m (the
                      nominal step's accuracy; default none; see 'sasnav
                      pair --help')
    --cross-extent M  along-track extent of the estimation grid (see
                      'sasnav pair --help')
    --range-extent M  range extent of the estimation grid (m, default 1.6;
                      without a gyro a longer grid tells yaw better on a
                      seabed that fills the swath: 4 m, 3x smaller yaw
                      errors for 2.5x the time; docs/estimator.md)
    --eta-max E       final eta above which a pair's verdict is 'failed'
                      (default 0.6; see 'sasnav pair --help')
    --coincidence F   compact scenes: a pair within F phase-centre spacings
                      of a coincidence is 'ambiguous' (default 0.5: all, 0 off;
                      with --virtual-array off unless given); compact
                      scenes also need an eta margin of 1.25 for 'ok' (see
                      'sasnav pair --help')
    --compact-contrast C  the contrast of p's image or q's above which a
                      pair's scene is compact for its verdict (default 4; 'inf':
                      never; see 'sasnav pair --help')
    --eta-outlier R   a consecutive pair on a speckle-like scene (both
                      contrasts at most the gate) whose eta exceeds R times
                      the median of the run's such pairs is 'ambiguous' at
                      best (default 1.6; > 1, or 'inf': off; needs 6 such
                      pairs; docs/navigation.md)
    --equalise M      each pair's search weights the images by their smoothed
                      intensity on speckle-like scenes where a feature stands
                      out (default 0.05 m; 0: off; see 'sasnav pair --help')
    --final C         each pair's final-stage criterion: auto (default), eta
                      or joint (see 'sasnav pair --help')
    --fix-yaw         hold each pair's yaw error at 0 (rail or plotter)
    --search-grid G   grid of each pair's search stages: auto (default),
                      fine or coarse (see 'sasnav pair --help')
    --no-aiding       ignore the run's aiding measurements
    --no-resolve      take each pair's own estimate (no joint resolution, no
                      fusion: the paper's method)
    --speed-lags M    per-ping EPCA Tx-array offsets scaled by the speed at
                      each ping: none (the run's offset), dvl (default:
                      from the aiding's DVL when the run has one, no
                      extra cost; otherwise none), pairs (the DVL, or
                      without one the pairs' own surges before their final
                      stage: every pair's final stage runs once the
                      offsets are known: about the time of the default)
    --tx-yaw M        channels with transmitters of their own: the yaw
                      between transmission and reception that turns each
                      transmitter: auto (default: from the gyro when the
                      run has one, otherwise from the pairs' own yaw
                      estimates and a second estimate of every ok pair),
                      pairs (from the pairs even with a gyro), none
    --aiding-bias S,W,Y  estimate a constant error of the aiding per ping
                      interval (a DVL's bias and scale factor) with these
                      standard deviations (m, m, rad; default
                      0.0004,0.0004,0: a 0.2 % DVL scale factor over a 0.2 m
                      step; 0,0,0: none)
    --motion-sigma S,W,Y  standard deviations of the change of the motion
                      error from one pair to the next (m, m, rad; default
                      0.01,0.01,0.01)
    --link-sigma S,W,Y  standard deviations of an ok pair's estimate in the
                      fusion (m, m, rad; default 0.001,0.00002,0.00005;
                      long baselines twice these); larger ones give the
                      aiding (without it, the motion model) more weight
                      (at about 5 dB and below the pairs' surge is biased:
                      docs/navigation.md, "Below 10 dB")
    --link-eta E      with aiding fused, a pair whose final eta exceeds E
                      has its standard deviations multiplied by
                      (eta / E)^2 where the aiding measures them: noisy
                      pairs (low SNR) weigh less against the aiding
                      (default 0.2; 0: off, every ok pair weighs
                      --link-sigma, as without aiding)
    --first-pose X,Y,YAW  place the trajectory so that the first ping's PCA
                      centroid is at this world pose (an external fix:
                      GNSS, USBL); default: the run's nominal first ping
    --anchor-truth    the same with the run's true first pose (simulations:
                      the written navigation then images on the truth's grid)
    --threads N       OpenMP threads (default: all cores); with several, pairs
                      are estimated concurrently (same results, bit for bit)
    --gpu             the pairs' error evaluations on a CUDA GPU (builds
                      configured with -DSASNAV_CUDA=ON; the same estimates to
                      float rounding: docs/estimator.md, "GPU")
    --checkpoint FILE  keep every pair estimate in FILE as it is made; if the
                      command is interrupted (Ctrl-C, kill, a crash), the same
                      command resumes from FILE and gives the same result
                      (docs/cli.md). FILE is removed once -o is written
    --json            machine-readable summary on stdout, with the
                      trajectory's formal standard deviations (formal_sigma:
                      the smoother's, as right as its weights; docs/
                      navigation.md, "Formal standard deviations")
  
  Virtual arrays (single-channel sonars, AirSAS; docs/navigation.md,
  "Virtual arrays"): K consecutive pings form one virtual ping of K x N
  channels, each with its own transmitter and receiver pose from the
  input navigation; the motion between virtual pings S pings apart is
  estimated and spread over the pings (corrections interpolated between
  the groups' middle pings):
    --virtual-array K pings per virtual ping (2..128 / channels)
    --interleave M    a virtual ping takes every M-th ping (default 1);
                      M = 2 with stride 1 compares interleaved groups
                      (pings 0,2,4,.. with 1,3,5,..): their apertures
                      overlap, 7-15x more precise than disjoint groups
                      on the simulated AirSAS, at K x M ping spacings of
                      aperture per group (keep it short enough for the
                      scene: grating lobes)
    --stride S        pings between virtual pings (default K when M = 1:
                      disjoint groups; 1 when M > 1. Groups sharing pings
                      tie the estimate to the input navigation)
    --iterations N    passes, each on the previous pass's navigation
                      (default 2)
    --closed          the track closes on itself (a full circle, a
                      turntable): groups wrap round, one more pair links
                      the last group to the first and the misclosure is
                      spread over the steps (a scale error stays)
    --keep-length     scale the estimated steps so that their total length
                      is the input navigation's: the estimates give the
                      track's shape, the input its length (the steps are
                      0.5-3 % too long on AirSAS-like layouts; right only
                      where the input's length is, docs/airsas.md)
    --align-heading   turn each group's layout so that its pings lie along
                      their headings (a gyro's; no crab): a smooth drift of
                      the input's positions tilts the layouts, and the
                      steps keep the tilt's sway without it (docs/airsas.md);
                      the turns are reported, with a warning when their
                      mean would move the track by over 1 mm (what a
                      crab or a heading bias would do to every step)
    --along-track input  keep the input's along-track (a DVL's, an INS's)
                      and correct only the across-track from the echoes:
                      each group moves along its normal by the chained
                      steps' sway; yaws stay the input's. Removes an
                      across-track drift down to the first group's own
                      error, keeps an along-track one (implies
                      --align-heading; default echoes: both axes)
    --estimate-yaw    estimate each step's yaw too (default: held at the
                      input navigation's: an omnidirectional group shows
                      its yaw only through its length)
    A flagged step (verdict not ok) keeps the input navigation's. The steps
    correct jumps and ping-to-ping errors of the input, not a smooth drift:
    both groups of a pair carry the input's layout error alike
    (docs/airsas.md).
    The estimation grid is square, centred at the run's range of interest,
    --cross-extent / --range-extent default 0.35 x that range (0.3 m for
    AirSAS); the search box is +-0.7 ping spacings in surge and sway.
    -o FILE           output navigation file (HDF5)
  
  Progress on stderr: a bar on a terminal, otherwise a line every 10 s
  (pairs done, rate, time left; SASNAV_PROGRESS_SECONDS sets the period).
  
  Survey scale: the run is read ping by ping (only the pings in flight are
  in memory). 'mpirun -np N sasnav navigate ...' spreads the pairs over N
  processes (one node or many); rank 0 gathers them and writes the same
  navigation as one process, bit for bit (docs/survey.md). --threads then
  counts per process; --checkpoint is for one process.

  $ sasnav refine --help
  usage: sasnav refine run.h5 nav.h5 -o refined.h5 [--grid X0,X1,NX,Y0,Y1,NY]
                       [--sweeps N] [--surge-range M] [--sway-range M] [--sparsity EPS]
                       [--window N] [--threads N] [--checkpoint FILE]
  
  Refines a navigation (the output of 'sasnav navigate', or any navigation
  file of the run's pings) with all pings together: for each ping in turn,
  a least-squares scene is fitted to the other pings' data, and the ping is
  moved along and across its array axis to best predict its own data from
  that scene (docs/navigation.md, 'Multi-ping refinement'). The common move
  of all pings is removed (not observable). The start must be within the
  search ranges of the truth (sway within about a quarter wavelength).
  Where the run holds the truth, prints the rms surge and sway errors
  before and after (after the rigid motion that best fits the centroids
  onto the true ones). The refinement is for scenes of a few strong
  scatterers (the tank); where the scenes explain the pings poorly (mean
  misfit above 0.3: an extended, speckle-like seabed) a warning says that
  its result is unreliable.
  
    --grid ...        scene grid (default: the nominal track's extent x range
                      of interest +-0.35 m, 5 mm pixels); it must hold the
                      scene's echoes and sample their band
    --sweeps N        sweeps over the pings at most (default 8)
    --sparsity EPS    reweighted damping of the scene, pixel i by
                      1 / (|s_i|^2 / mean |s|^2 + EPS) (default 0.01: a
                      scene of few strong scatterers; 0: uniform damping)
    --surge-range M   half-width of the surge search, m (default 0.012)
    --sway-range M    half-width of the sway search, m (default 0.0015)
    --window N        runs longer than N pings are refined in windows of N
                      pings, half overlapping, joined into one navigation;
                      memory and time per ping are those of one window
                      (default 64; 0: the whole run at once)
    --threads N       OpenMP threads (default: all cores)
    --checkpoint FILE  keep the refinement's state in FILE after every sweep;
                      the same command run again after an interruption
                      resumes from it with the same result (docs/cli.md).
                      FILE is removed once -o is written (runs of one window)
    -o FILE           output navigation (HDF5, with the run's truth if any)

  $ sasnav demo --help
  usage: sasnav demo [-o DIR] [--threads N] [--quick]
  
  Simulates the paper-trajectory preset (16 pings over 3 m, 30 dB SNR, true
  bistatic Tx/array poses), navigates it with the subspace-intersection
  estimator and with DPCA, backprojects it on one grid with the nominal,
  true and both estimated navigations (the estimated trajectories are
  placed on the true first ping, the one pose a pair estimator cannot
  know), and writes into DIR: run.h5, nav-subspace.h5, nav-dpca.h5,
  image-*.png, trajectory.png, error plots and report.md (errors, image
  correlations with the true-navigation image, timings).
  
    -o DIR        output directory (default: demo; created if missing)
    --threads N   OpenMP threads (default: all cores)
    --quick       6 pings and the estimator's coarse iterations only
                  (k = 2, i = 1): a smoke run of about a minute, not the
                  paper's accuracy

  $ sasnav validate --help
  usage: sasnav validate run.h5 -o DIR [--k-min K] [--k-max K]
                         [--fix-yaw | --yaw-sigma S] [--surge-sigma S] [--long-baselines]
                         [--k K] [--i I] [--refine [--sweeps N] [--sparsity EPS]]
                         [--grid X0,X1,NX,Y0,Y1,NY] [--threads N] [--gpu] [--json]
                         [--checkpoint FILE]
  
  The validation method of the paper's tank experiment (Sec. V): from a run
  whose pings step by whole phase-centre spacings (the tank: K = 7 of 8
  phase centres shared), builds the sub-sampled runs with K = k-min..k-max
  shared phase centres and all their phases, navigates each (every pair's
  estimate chained as it is, the paper's method: no joint resolution;
  pairs whose verdict is not "ok" are counted and warned about), combines the
  phases into one trajectory per K (placed on the largest K's, which is
  rotated by its fitted track angle), re-arranges the data into SISO (one
  receiver, all pings) and SIMO (every N-th ping, all receivers) apertures,
  images each with each trajectory and measures how well the complex
  images agree around the reflectors (docs/validation.md). On compact
  scenes such as the tank, hold the pair yaws (--fix-yaw). With --refine,
  every phase's pair trajectory is refined on the phase's own pings by the
  multi-ping data-domain fit of 'sasnav refine' (docs/navigation.md), and
  the spreads of the pair trajectories alone are reported too.
  Writes into DIR:
    validate.json       the summary (also on stdout with --json)
    trajectories.csv    ping, K, along-track, cross-track, yaw (aligned)
    pairs.csv           every pair estimate (motion error; its error vs the
                        truth when known), its margin, whether it sits at a
                        phase-centre coincidence, the contrasts of p's and
                        q's images (either above 4: compact-scene verdicts),
                        eta, whether that is far above its phase's
                        (navigate --eta-outlier), status and verdict,
                        whether the search was equalised and the peak of
                        its smoothed intensity (0 where not measured)
    trajectories.png    along/cross-track deviation from the mean of the K
    correlation.csv     pairwise image correlations (navigated images)
    siso_J.png, simo_J.png   images with the largest K's trajectory
    nominal_siso_0.png, nominal_simo_0.png   the same, nominal navigation
    report.md           tables and figures
  
    --k-min K, --k-max K  overlaps to test (default 4 .. the run's own)
    --fix-yaw          hold every pair's yaw error at 0 (rail, plotter)
    --yaw-sigma S      prior on the pair yaw error (rad; default none)
    --surge-sigma S    scale of a prior on the pair surge error (m; the
                       plotter's step accuracy; default none; the tank:
                       0.025, see docs/validation.md)
    --long-baselines   also estimate the pairs two steps apart within each
                       sub-sampled run (where they share phase centres) and
                       combine by least squares
    --k K, --i I       estimator iterations of the final stage (default 8, 8)
    --refine           refine each phase on its own pings (see above)
    --sweeps N         refinement sweeps at most (default 8)
    --sparsity EPS     the refinement's reweighted scene damping (default
                       0.01; 0: uniform; see sasnav refine --help)
    --grid ...         image grid (default: the track's extent x range of
                       interest +-0.35 m, 5 mm pixels)
    --threads N        OpenMP threads (default: all cores)
    --gpu              the pair estimates' error evaluations on a CUDA GPU
                       (builds configured with -DSASNAV_CUDA=ON)
    --json             print the summary on stdout
    --checkpoint FILE  keep every pair estimate in FILE as it is made; an
                       interrupted validation run again with the same
                       command resumes from FILE (the same results; the
                       refinement and the images are redone). FILE is
                       removed once the outputs are written
  
  Progress on stderr (pairs estimated, rate): a status line on a terminal,
  otherwise a line every 10 s (SASNAV_PROGRESS_SECONDS sets the period).

Help goes to standard output; nothing on standard error, exit status 0.

  $ sasnav navigate --help 2>&1 >/dev/null
