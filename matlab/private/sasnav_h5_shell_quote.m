function q = sasnav_h5_shell_quote(s)
% SASNAV_H5_SHELL_QUOTE  s as one POSIX shell word ('...', quotes escaped).
q = ['''' strrep(s, '''', '''\''''') ''''];
end
