function t = sasnav_h5_tree(file)
% SASNAV_H5_TREE  Structure of an HDF5 file: every dataset and attribute.
%
%   t = sasnav_h5_tree(file) returns a struct with
%     t.backend     'native' (h5info / h5read) or 'h5dump' (see README.md)
%     t.file        the file name
%     t.datasets    struct array: path ('/nav/tx'), kind ('real', 'complex'
%                   or 'int'), dims (HDF5 / C order, slowest first; [] for
%                   a scalar), and for the h5dump backend: class (fread
%                   precision of a value or of a complex member) and
%                   order ([index of r, index of i] among the members)
%     t.attributes  struct array: object ('/' for the root, '/system',
%                   '/image' ...), name, value (char for strings, double
%                   for numbers)
%
% Private helper of the sasnav readers (sasnav_read_run, sasnav_read_nav,
% sasnav_read_image).

if ~ischar(file) || isempty(file)
    error('sasnav:arg', 'sasnav: the file name must be a non-empty char array');
end
if exist(file, 'file') ~= 2
    error('sasnav:io', 'sasnav: %s: no such file', file);
end
t.file = file;
t.backend = sasnav_h5_backend();
t.datasets = struct('path', {}, 'kind', {}, 'dims', {}, 'class', {}, 'order', {});
t.attributes = struct('object', {}, 'name', {}, 'value', {});
if strcmp(t.backend, 'native')
    t = walk_info(t, h5info(file), '');
else
    t = parse_h5dump(t);
end
end

% --- native: h5info ------------------------------------------------------

function t = walk_info(t, g, prefix)
% g: a group as h5info returns it (g.Name is its full path).
obj = g.Name;
for k = 1:numel(g.Attributes)
    t.attributes(end + 1) = struct('object', obj, 'name', g.Attributes(k).Name, ...
                                   'value', attr_value(g.Attributes(k).Value));
end
for k = 1:numel(g.Datasets)
    d = g.Datasets(k);
    path = [prefix '/' d.Name];
    switch d.Datatype.Class
        case 'H5T_COMPOUND', kind = 'complex';
        case 'H5T_INTEGER', kind = 'int';
        otherwise, kind = 'real';
    end
    % h5info lists the sizes in MATLAB order (fastest first).
    dims = fliplr(double(d.Dataspace.Size(:)'));
    t.datasets(end + 1) = struct('path', path, 'kind', kind, 'dims', dims, 'class', '', ...
                                 'order', []);
    for a = 1:numel(d.Attributes)
        t.attributes(end + 1) = struct('object', path, 'name', d.Attributes(a).Name, ...
                                       'value', attr_value(d.Attributes(a).Value));
    end
end
for k = 1:numel(g.Groups)
    t = walk_info(t, g.Groups(k), g.Groups(k).Name);
end
end

function v = attr_value(v)
% Strings as char rows (fixed-length strings may keep their NUL; variable
% length ones come as a cell in some MATLAB versions), numbers as double.
if iscell(v)
    v = v{1};
end
if isa(v, 'string')
    v = char(v);
end
if ischar(v)
    nul = find(v == char(0), 1);
    if ~isempty(nul)
        v = v(1:nul - 1);
    end
    v = deblank(v(:)');
else
    v = double(v);
end
end

% --- fallback: h5dump (hdf5-tools) ---------------------------------------

function t = parse_h5dump(t)
% `h5dump -A` prints the header (groups, datasets, their types and shapes)
% and every attribute with its value; -m %.17g prints floats exactly, -w 0
% never wraps lines.
[status, out] = system(sprintf('h5dump -w 0 -m %%.17g -A %s 2>&1', sasnav_h5_shell_quote(t.file)));
if status ~= 0
    error('sasnav:format', 'sasnav: %s: h5dump cannot read it: %s', t.file, strtrim(out));
end
lines = regexp(out, '\r?\n', 'split');
stack = cell(0, 2); % open blocks: {kind, name} rows; kind GROUP/DATASET/ATTRIBUTE/other
paths = {};        % full path of each open GROUP/DATASET block ('' for other)
cur_ds = 0;        % index of the dataset whose block is open, 0 if none
cur_attr = 0;      % index of the attribute whose block is open, 0 if none
attr_type = '';    % 'string' or 'number'
attr_vals = {};
in_compound = 0;
members = cell(0, 2); % {type, name} of the compound members
in_data = 0;
for n = 1:numel(lines)
    s = strtrim(lines{n});
    if isempty(s)
        continue;
    end
    tok = regexp(s, '^(GROUP|DATASET|ATTRIBUTE) "(.*)" \{$', 'tokens', 'once');
    if ~isempty(tok)
        kind = tok{1};
        name = tok{2};
        parent = last_path(paths);
        if strcmp(kind, 'GROUP') && strcmp(name, '/')
            path = '';
        else
            path = [parent '/' name];
        end
        stack(end + 1, :) = {kind, name};
        if strcmp(kind, 'ATTRIBUTE')
            paths{end + 1} = '';
            obj = parent;
            if isempty(obj)
                obj = '/';
            end
            t.attributes(end + 1) = struct('object', obj, 'name', name, 'value', []);
            cur_attr = numel(t.attributes);
            attr_type = 'number';
            attr_vals = {};
        else
            paths{end + 1} = path;
            if strcmp(kind, 'DATASET')
                t.datasets(end + 1) = struct('path', path, 'kind', '', 'dims', [], ...
                                             'class', '', 'order', []);
                cur_ds = numel(t.datasets);
            end
        end
        continue;
    end
    if strcmp(s, '}')
        if isempty(stack)
            continue;   % the closing brace of `HDF5 "file" {`
        end
        kind = stack{end, 1};
        if strcmp(kind, 'ATTRIBUTE')
            t.attributes(cur_attr).value = finish_attr(attr_type, attr_vals);
            cur_attr = 0;
        elseif strcmp(kind, 'DATASET')
            cur_ds = 0;
        elseif in_compound && cur_attr == 0 && cur_ds > 0
            t.datasets(cur_ds) = finish_compound(t.datasets(cur_ds), members, t.file);
            in_compound = 0;
        end
        if strcmp(stack{end, 2}, 'DATA {')
            in_data = 0;
        end
        stack(end, :) = [];
        paths(end) = [];
        continue;
    end
    if s(end) == '{'
        % a nested block: DATATYPE H5T_COMPOUND {, DATATYPE H5T_STRING {, DATA {
        if cur_attr > 0 && strncmp(s, 'DATATYPE', 8)
            if ~isempty(strfind(s, 'H5T_STRING'))
                attr_type = 'string';
            end
        elseif cur_ds > 0 && strncmp(s, 'DATATYPE', 8)
            if ~isempty(strfind(s, 'H5T_COMPOUND'))
                in_compound = 1;
                members = cell(0, 2);
            else
                error('sasnav:format', 'sasnav: %s: %s: unsupported type (%s)', t.file, ...
                      t.datasets(cur_ds).path, s);
            end
        elseif strcmp(s, 'DATA {')
            in_data = 1;
        end
        stack(end + 1, :) = {'other', s};
        paths{end + 1} = '';
        continue;
    end
    if cur_attr > 0
        if in_data
            attr_vals{end + 1} = s;
        end
        continue;
    end
    if cur_ds > 0
        if in_compound
            m = regexp(s, '^(\S+) "(.*)";$', 'tokens', 'once');
            if ~isempty(m)
                members(end + 1, :) = m;
            end
        elseif strncmp(s, 'DATATYPE', 8)
            [t.datasets(cur_ds).kind, t.datasets(cur_ds).class] = ...
                atomic_type(strtrim(s(9:end)), t.file, t.datasets(cur_ds).path);
        elseif strncmp(s, 'DATASPACE', 9)
            t.datasets(cur_ds).dims = dataspace_dims(s);
        end
    end
end
end

function p = last_path(paths)
p = '';
for k = numel(paths):-1:1
    if ~isempty(paths{k}) || k == 1
        p = paths{k};
        return;
    end
end
end

function [kind, cls] = atomic_type(s, file, path)
tok = regexp(s, '^H5T_IEEE_F(32|64)(LE|BE)$', 'tokens', 'once');
if ~isempty(tok)
    kind = 'real';
    if strcmp(tok{1}, '32'), cls = 'single'; else, cls = 'double'; end
    return;
end
tok = regexp(s, '^H5T_STD_([IU])(8|16|32|64)(LE|BE)$', 'tokens', 'once');
if ~isempty(tok)
    kind = 'int';
    if tok{1} == 'U', cls = ['uint' tok{2}]; else, cls = ['int' tok{2}]; end
    return;
end
error('sasnav:format', 'sasnav: %s: %s: unsupported type %s', file, path, s);
end

function d = finish_compound(d, members, file)
% A complex dataset: exactly two float members named r and i, same size.
names = {};
if size(members, 1) == 2
    names = members(:, 2)';
end
ir = find(strcmp(names, 'r'));
ii = find(strcmp(names, 'i'));
if numel(ir) ~= 1 || numel(ii) ~= 1
    error('sasnav:format', ['sasnav: %s: %s must be a compound of exactly two float ' ...
                            'members "r" and "i"'], file, d.path);
end
[k1, c1] = atomic_type(members{1, 1}, file, d.path);
[k2, c2] = atomic_type(members{2, 1}, file, d.path);
if ~strcmp(k1, 'real') || ~strcmp(k2, 'real') || ~strcmp(c1, c2)
    error('sasnav:format', ['sasnav: %s: %s: members of different or non-float types are ' ...
                            'not supported by the h5dump fallback'], file, d.path);
end
d.kind = 'complex';
d.class = c1;
d.order = [ir ii];
end

function dims = dataspace_dims(s)
% 'DATASPACE  SIMPLE { ( 3, 16, 241 ) / ( ... ) }' or 'DATASPACE  SCALAR'
tok = regexp(s, '\(([^)]*)\)', 'tokens', 'once');
if isempty(tok)
    dims = [];
else
    dims = str2double(strsplit(tok{1}, ','));
end
end

function v = finish_attr(type, vals)
% vals: the lines of DATA { ... }, each '(i): v, v, ...'
text = '';
for k = 1:numel(vals)
    s = regexprep(vals{k}, '^\([0-9, ]*\):\s*', '');
    if k > 1
        text = [text ', '];
    end
    text = [text s];
end
if strcmp(type, 'string')
    q = find(text == '"');
    if numel(q) >= 2
        v = text(q(1) + 1:q(end) - 1);
    else
        v = text;
    end
else
    if isempty(strtrim(text))
        v = [];
    else
        v = str2double(strtrim(strsplit(text, ',')));
        v = v(:);
    end
end
end
