#!/bin/sh
# Runs a C or C++ host of the gear FMU on the Python environment of PYTHON, as README.md says
# (The FMU, What a host needs): usage  run.sh PYTHON HOST [HOST'S ARGUMENTS...]
set -e
python=$1
shift
# pythonfmu's binary does not link libpython: load the environment's interpreter library first
LD_PRELOAD=$("$python" -c 'import sysconfig as s; print(s.get_config_var("LIBDIR") + "/" + s.get_config_var("LDLIBRARY"))')
# the environment's packages (numpy, scipy, numba); no PYTHONHOME: the standard library comes
# from libpython's own prefix, and a venv has none (PYTHONHOME=venv: "No module named 'encodings'")
PYTHONPATH=$("$python" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
export LD_PRELOAD PYTHONPATH
unset PYTHONHOME
exec "$@"
