function run = sasnav_read_run(file)
% SASNAV_READ_RUN  Read a sasnav run file (format "sasnav-run",
% docs/format.md) in MATLAB or GNU Octave.
%
%   run = sasnav_read_run('run.h5')
%
% Every dataset and attribute of the file, with the index order of
% docs/format.md (C / HDF5 order, indices from 1):
%   run.raw            complex single, n_pings x n_rx x n_samples:
%                      run.raw(p, l, m) is sample m of receiver l of ping p
%                      (/raw [ping][rx][sample]); squeeze(run.raw(p, l, :))
%                      is one channel, permute(run.raw, [3 2 1]) gives
%                      n_samples x n_rx x n_pings (h5read's order)
%   run.n_pings, run.n_rx, run.n_samples   its dimensions
%   run.system         the /system attributes: sound_speed, f0, bandwidth,
%                      sample_rate, taper, attenuation, beam_pattern, t0,
%                      ping_spacing, speed, tx_lag, range_of_interest
%   run.array          the /array attributes (rx_length, tx_length,
%                      rx_height, tx_height) and rx_u (n_rx x 1); with
%                      channels of their own sizes (format version 2)
%                      also sizes (n_rx x 4: rx_length, tx_length,
%                      rx_height, tx_height of each channel)
%   run.nav.tx, run.nav.array        n_pings x 3, columns x, y, theta
%   run.truth.tx, run.truth.array    the same (only when /truth exists)
%   run.aiding.time, .yaw_rate, .yaw_rate_sigma (n_pings x 1) and
%   .velocity, .velocity_sigma (n_pings x 2)  (only what /aiding holds)
%   run.channels.tx, run.channels.array   n_rx x 3: each channel's
%                      transmitter and array pose relative to its ping's
%                      (format version 2, only when /channels exists)
%   run.format, run.format_version, run.created_by   root attributes
%   run.attributes.<dataset>   attributes of each dataset, e.g.
%                      run.attributes.nav_tx.units = 'm, m, rad'
% Sample m of a channel is at time run.system.t0 + (m - 1) / sample_rate.
% Any other dataset or group in the file appears the same way.
%
% Uses h5info / h5read where they exist (MATLAB), otherwise the h5dump
% tool (GNU Octave; see matlab/README.md).
[run, t] = sasnav_h5_load(file, {'sasnav-run'});
if ~isfield(run, 'raw') || ~isfield(run, 'nav') || ~isfield(run, 'system') || ~isfield(run, 'array')
    error('sasnav:format', 'sasnav: %s: a run needs /raw, /nav, /system and /array', file);
end
if ~strcmp(t.datasets(strcmp({t.datasets.path}, '/raw')).kind, 'complex')
    error('sasnav:format', 'sasnav: %s: /raw must be complex (compound {r, i})', file);
end
sz = size(run.raw);
sz(end + 1:3) = 1;
run.n_pings = sz(1);
run.n_rx = sz(2);
run.n_samples = sz(3);
end
