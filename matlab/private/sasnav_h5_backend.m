function b = sasnav_h5_backend()
% SASNAV_H5_BACKEND  How the sasnav readers read HDF5: 'native' or 'h5dump'.
%
% 'native' uses h5info / h5read (MATLAB; any Octave that provides both);
% 'h5dump' runs the h5dump tool of the HDF5 distribution (Debian package
% hdf5-tools) and reads its binary output, for GNU Octave, whose core has
% no h5read. The environment variable SASNAV_H5_BACKEND (native or h5dump)
% overrides the choice.
b = getenv('SASNAV_H5_BACKEND');
if isempty(b)
    if exist('h5info') && exist('h5read')
        b = 'native';
    else
        b = 'h5dump';
    end
end
if ~any(strcmp(b, {'native', 'h5dump'}))
    error('sasnav:arg', 'sasnav: SASNAV_H5_BACKEND must be native or h5dump, not "%s"', b);
end
end
