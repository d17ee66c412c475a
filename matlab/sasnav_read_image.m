function [img, x, y, info] = sasnav_read_image(file)
% SASNAV_READ_IMAGE  Read a sasnav image file (format "sasnav-image",
% docs/format.md) in MATLAB or GNU Octave.
%
%   [img, x, y, info] = sasnav_read_image('image.h5')
%   imagesc(x, y, 20 * log10(abs(img))); axis xy; axis image
%
%   img    complex single, ny x nx: img(iy, ix) is the pixel at
%          (x(ix), y(iy)), rows along range y, columns along track x
%          (/image [ny][nx])
%   x      nx x 1, along-track pixel centres (m)
%   y      ny x 1, range pixel centres (m)
%   info   everything else: info.x0, info.dx, info.y0, info.dy (the grid,
%          from the /image attributes, or from /x and /y when a file written
%          by another tool lacks them), info.format, info.format_version,
%          info.created_by, info.attributes.image.units ...
%
% With the grid attributes, x = x0 + (0:nx-1)' * dx and y likewise, as the
% C reader computes them (bit-exact); /x and /y are checked against them.
% See sasnav_read_run for the backends (h5read or h5dump).
[s, t] = sasnav_h5_load(file, {'sasnav-image'});
if ~isfield(s, 'image') || ~isfield(s, 'x') || ~isfield(s, 'y')
    error('sasnav:format', 'sasnav: %s: an image needs /image, /x and /y', file);
end
img = s.image;
if ~strcmp(t.datasets(strcmp({t.datasets.path}, '/image')).kind, 'complex')
    error('sasnav:format', 'sasnav: %s: /image must be complex (compound {r, i})', file);
end
[ny, nx] = size(img);
if numel(s.x) ~= nx || numel(s.y) ~= ny
    error('sasnav:format', 'sasnav: %s: /x has %d values and /y %d for a %d x %d image', ...
          file, numel(s.x), numel(s.y), ny, nx);
end
info = rmfield(s, {'image', 'x', 'y'});
a = struct();
if isfield(s.attributes, 'image')
    a = s.attributes.image;
end
if all(isfield(a, {'x0', 'dx', 'y0', 'dy'}))
    info.x0 = a.x0;
    info.dx = a.dx;
    info.y0 = a.y0;
    info.dy = a.dy;
    x = info.x0 + (0:nx - 1)' * info.dx;
    y = info.y0 + (0:ny - 1)' * info.dy;
    % the C reader's check: within 1e-6 of a pixel
    if any(abs(x - s.x(:)) > 1e-6 * abs(info.dx) + 1e-12 * abs(x)) || ...
       any(abs(y - s.y(:)) > 1e-6 * abs(info.dy) + 1e-12 * abs(y))
        error('sasnav:format', 'sasnav: %s: /x or /y disagree with the /image grid attributes', file);
    end
else
    x = s.x(:);
    y = s.y(:);
    info.x0 = x(1);
    info.y0 = y(1);
    info.dx = 0;
    info.dy = 0;
    if nx > 1
        info.dx = (x(end) - x(1)) / (nx - 1);
    end
    if ny > 1
        info.dy = (y(end) - y(1)) / (ny - 1);
    end
end
end
