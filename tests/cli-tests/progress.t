Progress of long commands when standard error is not a terminal: a line
every SASNAV_PROGRESS_SECONDS (default 10 s; 0: every update) with the
count, the rate and the time left, and a last line at the end.

  $ SASNAV_PROGRESS_SECONDS=0 sasnav navigate run.h5 --method aiding --threads 1 -o p.h5 2>&1 >/dev/null | head -n 2
  sasnav navigate: 1/16 pairs, * pairs/s, * left (glob)
  sasnav navigate: 2/16 pairs, * pairs/s, * left (glob)
  $ SASNAV_PROGRESS_SECONDS=0 sasnav navigate run.h5 --method aiding --threads 1 -o p.h5 2>&1 >/dev/null | grep "16/16"
  sasnav navigate: 16/16 pairs, * pairs/s (glob)

With the default period a short job prints no progress line:

  $ sasnav navigate run.h5 --method aiding -o p.h5 2>&1 >/dev/null | grep -c "pairs/s"
  0
  [1]

simulate and image count pings:

  $ SASNAV_PROGRESS_SECONDS=0 sasnav simulate --preset point -o s.h5 2>&1 | grep "^sasnav simulate: 17/17"
  sasnav simulate: 17/17 pings, * pings/s (glob)
  $ SASNAV_PROGRESS_SECONDS=0 sasnav image run.h5 -o i.h5 2>&1 | grep "^sasnav image: 1/17"
  sasnav image: 1/17 pings, * pings/s, * left (glob)
