#!/usr/bin/env bash
# The Python package as a user installs it: `pip install ./clients/python` into a fresh venv with
# no network (--no-index: pip may download nothing; the build backend needs nothing), then the
# Python tests (test_python.py) run against that installed package, not the source tree. The
# venv sees Debian's python3-numpy, so poses give arrays here (test_python.py also runs without
# NumPy, from the source tree, as ipc_python_client).
#   python_package.sh SOURCE_DIR WORK_DIR   (HANDTRACK_CLIENT_LIB, IPC_TEST_WRITER, HANDTRACK_EXAMPLE set)
set -euo pipefail
src="$1" work="$2"
rm -rf "$work" && mkdir -p "$work"
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
"$work/venv/bin/python" -m pip install --no-index --no-cache-dir --disable-pip-version-check -q "$src/clients/python"
"$work/venv/bin/python" -c 'import numpy' 2>/dev/null || { echo "FAIL: no NumPy in the venv (python3-numpy)"; exit 1; }
cd "$work"
env -u PYTHONPATH HANDTRACK_EXPECT_INSTALLED="$work/venv" PYTHONDONTWRITEBYTECODE=1 \
  "$work/venv/bin/python" "$src/tests/ipc/test_python.py"
