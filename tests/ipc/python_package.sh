#!/usr/bin/env bash
# The Python package as a user installs it: `pip install ./clients/python` into a fresh venv with
# no network (--no-index: pip may download nothing; the build backend needs nothing), then the
# Python tests (test_python.py) run against that installed package, not the source tree. The
# venv sees Debian's python3-numpy, so hands give arrays here (test_python.py also runs without
# NumPy, from the source tree, as ipc_python_client).
# Last, the installed package reads frames from a real handtrackd (synthetic camera): their hands
# list holds the camera's right hand.
#   python_package.sh SOURCE_DIR WORK_DIR HANDTRACKD
#   (HANDTRACK_CLIENT_LIB, IPC_TEST_WRITER, HANDTRACK_EXAMPLE set)
set -euo pipefail
src="$1" work="$2" handtrackd="$3"
rm -rf "$work" && mkdir -p "$work"
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
"$work/venv/bin/python" -m pip install --no-index --no-cache-dir --disable-pip-version-check -q "$src/clients/python"
"$work/venv/bin/python" -c 'import numpy' 2>/dev/null || { echo "FAIL: no NumPy in the venv (python3-numpy)"; exit 1; }
cd "$work"
env -u PYTHONPATH HANDTRACK_EXPECT_INSTALLED="$work/venv" PYTHONDONTWRITEBYTECODE=1 \
  "$work/venv/bin/python" "$src/tests/ipc/test_python.py"

name="htpy-daemon-$$"
"$handtrackd" --config "$src/data/handtrackd.toml" --source synthetic:pinch --shm-name "$name" --log-level warn \
  > "$work/daemon.log" 2>&1 &
daemon=$!
trap 'kill $daemon 2>/dev/null; wait $daemon 2>/dev/null; rm -f /dev/shm/$name' EXIT
env -u PYTHONPATH timeout 60 "$work/venv/bin/python" - "$name" <<'PY'
import sys
import handtrack
client = handtrack.Client.wait_for(sys.argv[1], timeout=30)
frames = [f for _, f in zip(range(10), client.frames(timeout=10))]
assert len(frames) == 10, len(frames)
hands = [h for f in frames for h in f.hands]
tracked = [h for h in hands if h.state_name == "tracking"]
assert tracked and tracked[-1].joints.shape == (21, 3), [f.to_dict()["hands"] for f in frames]
# The synthetic camera renders one right hand: a list of one hand per frame, with its id and side.
assert all(len(f.hands) <= 1 for f in frames), [len(f.hands) for f in frames]
assert tracked[-1].handedness == "right" and tracked[-1].hand_id > 0, tracked[-1].to_dict()
print(f"installed package: {len(frames)} frames from handtrackd, {len(hands)} hands "
      f"({tracked[-1].handedness}, id {tracked[-1].hand_id}), joints as {type(tracked[-1].joints).__name__}")
PY
