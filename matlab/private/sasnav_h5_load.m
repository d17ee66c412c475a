function [s, t] = sasnav_h5_load(file, formats, groups)
% SASNAV_H5_LOAD  A sasnav HDF5 file as a nested struct.
%
%   [s, t] = sasnav_h5_load(file, formats, groups)
%   Checks the root attributes `format` (one of the cell array `formats`)
%   and `format_version` (1 or 2: run files with /channels), then maps the file onto s:
%     * a group is a struct field (s.nav, s.system ...) holding its
%       attributes (s.system.sound_speed) and its members;
%     * a dataset is a field holding its values (sasnav_h5_data: the index
%       order of the file, complex single for {r, i}, double otherwise);
%     * the attributes of a dataset /a/b go to s.attributes.a_b
%       (s.attributes.nav_tx.units = 'm, m, rad');
%     * root attributes are fields of s (s.format, s.format_version,
%       s.created_by).
%   groups: optional cell array of top-level names ('nav', 'truth',
%   'nav_sigma'): only datasets under those, or of those names at the
%   root, are read (the others are not loaded at all).
%   t is the file's tree (sasnav_h5_tree).
if nargin < 3
    groups = {};
end
t = sasnav_h5_tree(file);
s = struct();
for k = 1:numel(t.attributes)
    a = t.attributes(k);
    if strcmp(a.object, '/')
        s.(field_name(a.name)) = a.value;
    end
end
if ~isfield(s, 'format') || ~ischar(s.format)
    error('sasnav:format', 'sasnav: %s: no string attribute "format" at the root: not a sasnav file', file);
end
if ~any(strcmp(s.format, formats))
    error('sasnav:format', 'sasnav: %s: format is "%s", expected %s', file, s.format, ...
          strjoin(strcat('"', formats, '"'), ' or '));
end
if ~isfield(s, 'format_version') || ~(isequal(s.format_version, 1) || isequal(s.format_version, 2))
    error('sasnav:format', 'sasnav: %s: format_version must be 1 or 2', file);
end
s.attributes = struct();
for k = 1:numel(t.datasets)
    d = t.datasets(k);
    parts = strsplit(d.path(2:end), '/');
    if ~isempty(groups) && ~any(strcmp(parts{1}, groups))
        continue;
    end
    s = set_path(s, parts, sasnav_h5_data(t, d));
end
for k = 1:numel(t.attributes)
    a = t.attributes(k);
    if strcmp(a.object, '/')
        continue;
    end
    parts = strsplit(a.object(2:end), '/');
    if ~isempty(groups) && ~any(strcmp(parts{1}, groups))
        continue;
    end
    if any(strcmp(a.object, {t.datasets.path}))
        key = field_name(strjoin(parts, '_'));
        if ~isfield(s.attributes, key)
            s.attributes.(key) = struct();
        end
        s.attributes.(key).(field_name(a.name)) = a.value;
    else
        s = set_path(s, [parts {a.name}], a.value);
    end
end
end

function s = set_path(s, parts, value)
f = field_name(parts{1});
if numel(parts) == 1
    s.(f) = value;
    return;
end
if ~isfield(s, f) || ~isstruct(s.(f))
    s.(f) = struct();
end
s.(f) = set_path(s.(f), parts(2:end), value);
end

function f = field_name(name)
f = regexprep(name, '[^A-Za-z0-9_]', '_');
if isempty(f) || ~isletter(f(1))
    f = ['x' f];
end
end
