#!/bin/sh
# ctest python_pip_install: `pip install .` of this source checkout into a fresh virtual
# environment (Debian's numpy, pytest, distributed seen through --system-site-packages; no
# package index), reusing the build tree's extension, then the pytest suite against the
# installed package, from outside the source tree.
# Usage: pip_install_test.sh SOURCE_DIR BUILD_DIR PYTHON
set -eu
src=$1 build=$2 python=$3
work=$build/pip-install-test
rm -rf "$work"
"$python" -m venv --system-site-packages "$work/venv"
GRADEL_CMAKE_BUILD_DIR=$build "$work/venv/bin/python" -m pip install --quiet --no-build-isolation --no-index "$src"
cd "$work"
"$work/venv/bin/python" - <<PY
import gradel, gradel.study, os
where = os.path.realpath(gradel.__file__)
assert where.startswith(os.path.realpath("$work/venv")), "gradel imported from " + where
for f in ("py.typed", "gradel.pyi"):
    assert os.path.exists(os.path.join(os.path.dirname(where), f)), f + " not installed"
print("installed:", where)
PY
GRADEL_SOURCE_DIR=$src PYTHONDONTWRITEBYTECODE=1 exec "$work/venv/bin/python" -m pytest -q -p no:cacheprovider "$src/python/tests"
