function nav = sasnav_read_nav(file)
% SASNAV_READ_NAV  Read the navigation of a sasnav navigation file
% (format "sasnav-nav", the output of `sasnav navigate`) or of a run file
% (its /nav and /truth only; /raw is not read), in MATLAB or GNU Octave.
%
%   nav = sasnav_read_nav('nav.h5')
%
%   nav.tx, nav.array     n_pings x 3: pose (x, y, theta) of the
%                         transmitter at transmission and of the array
%                         midpoint at reception, per ping (/nav/tx,
%                         /nav/array [n_pings][3]); metres, radians
%   nav.truth.tx, nav.truth.array   the true poses, only when the file
%                         has /truth (isfield(nav, 'truth'))
%   nav.sigma             n_pings x 3: the navigation's formal standard
%                         deviations of each PCA centroid relative to the
%                         first (along, across track, yaw; /nav_sigma),
%                         only when the file has them
%   nav.n_pings
%   nav.format, nav.format_version, nav.created_by   root attributes
%   nav.attributes.nav_tx.units ...   the attributes of each dataset
%
% See sasnav_read_run for the backends (h5read or h5dump).
s = sasnav_h5_load(file, {'sasnav-nav', 'sasnav-run'}, {'nav', 'truth', 'nav_sigma'});
if ~isfield(s, 'nav') || ~isfield(s.nav, 'tx') || ~isfield(s.nav, 'array')
    error('sasnav:format', 'sasnav: %s: no /nav/tx and /nav/array', file);
end
nav = struct();
nav.tx = s.nav.tx;
nav.array = s.nav.array;
if isfield(s, 'truth')
    nav.truth = s.truth;
end
if isfield(s, 'nav_sigma')
    nav.sigma = s.nav_sigma;
end
nav.n_pings = size(nav.tx, 1);
nav.format = s.format;
nav.format_version = s.format_version;
if isfield(s, 'created_by')
    nav.created_by = s.created_by;
end
nav.attributes = s.attributes;
if size(nav.tx, 2) ~= 3 || ~isequal(size(nav.array), size(nav.tx))
    error('sasnav:format', 'sasnav: %s: /nav/tx and /nav/array must be [n_pings][3]', file);
end
if isfield(nav, 'sigma') && ~isequal(size(nav.sigma), size(nav.tx))
    error('sasnav:format', 'sasnav: %s: /nav_sigma must be [n_pings][3] as /nav', file);
end
end
