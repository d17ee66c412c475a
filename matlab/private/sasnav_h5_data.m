function a = sasnav_h5_data(t, d)
% SASNAV_H5_DATA  The values of dataset d (an entry of sasnav_h5_tree's
% t.datasets), with the index order of the file (C / HDF5 order,
% docs/format.md): a [n][k] dataset gives an n x k array, [p][l][m] a
% p x l x m array; a one-dimensional dataset gives a column.
% Complex datasets (compound {r, i}) give complex single arrays (members
% stored as float64 are converted, as the C readers do); real ones double.
dims = d.dims;
if any(dims == 0)
    if numel(dims) >= 2
        a = zeros(dims);
    else
        a = zeros(0, 1);
    end
    return;
end
if strcmp(t.backend, 'native')
    v = h5read(t.file, d.path);
    if isstruct(v)
        v = complex(single(v.r), single(v.i));
    else
        v = double(v);
    end
    % h5read reverses the dimensions (column-major): undo it. Its result
    % has the reversed shape (trailing singleton dimensions dropped); the
    % shape from h5info is the fallback for a value that came back flat.
    k = numel(dims);
    if k >= 2
        md = size(v);
        md(end + 1:k) = 1;
        if numel(md) ~= k || ~(isequal(md, dims) || isequal(md, fliplr(dims)))
            md = fliplr(dims);
        end
        a = permute(reshape(v, md), k:-1:1);
    else
        a = v(:);
    end
    a = keep_complex(a, d);
    return;
end
% h5dump -b NATIVE writes the values in C order and native byte order:
% for a compound, the members interleaved in the file's member order.
tmp = [tempname() '.bin'];
cmd = sprintf('h5dump -d %s -b NATIVE -o %s %s 2>&1', sasnav_h5_shell_quote(d.path), ...
              sasnav_h5_shell_quote(tmp), sasnav_h5_shell_quote(t.file));
[status, out] = system(cmd);
fid = -1;
if status == 0
    fid = fopen(tmp, 'r');
end
if fid < 0
    if exist(tmp, 'file')
        delete(tmp);
    end
    error('sasnav:format', 'sasnav: %s: h5dump cannot read %s: %s', t.file, d.path, strtrim(out));
end
n = prod(dims);
if strcmp(d.kind, 'complex')
    v = fread(fid, 2 * n, [d.class '=>' d.class]);
else
    v = fread(fid, n, [d.class '=>double']);
end
fclose(fid);
delete(tmp);
if strcmp(d.kind, 'complex')
    if numel(v) ~= 2 * n
        error('sasnav:format', 'sasnav: %s: %s: h5dump gave %d values, expected %d', t.file, ...
              d.path, numel(v), 2 * n);
    end
    v = reshape(v, 2, n);
    v = complex(single(v(d.order(1), :)), single(v(d.order(2), :)));
elseif numel(v) ~= n
    error('sasnav:format', 'sasnav: %s: %s: h5dump gave %d values, expected %d', t.file, ...
          d.path, numel(v), n);
end
if numel(dims) >= 2
    % C order: the last index varies fastest.
    a = permute(reshape(v, fliplr(dims)), numel(dims):-1:1);
elseif isempty(dims)
    a = v(1);
else
    a = v(:);
end
a = keep_complex(a, d);
end

function a = keep_complex(a, d)
% Octave turns a complex array whose imaginary parts are all zero into a
% real one (e.g. in permute); a complex dataset stays complex here.
if strcmp(d.kind, 'complex') && isreal(a)
    a = complex(a);
end
end
