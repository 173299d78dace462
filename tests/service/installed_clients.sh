#!/usr/bin/env bash
# Out-of-tree: `cmake --install` BUILD into a scratch prefix; check the FHS layout there; build the
# installed client examples (share/handtrack/examples) with find_package(handtrack) and with
# pkg-config; start the INSTALLED handtrackd on the synthetic camera; run the C, C++, Python and
# pinch-to-click examples against it and check what they print.
#   installed_clients.sh BUILD_DIR WORK_DIR
set -euo pipefail
build="$1" work="$2"
rm -rf "$work" && mkdir -p "$work"
prefix="$work/prefix"
fail() { echo "FAIL: $*"; exit 1; }

t0=$SECONDS
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in sbin/handtrackd bin/handtrack-cat include/handtrack/client.h include/handtrack/client.hpp \
         lib/systemd/system/handtrackd.service lib/udev/rules.d/59-handtrack-cameras.rules \
         lib/sysusers.d/handtrack.conf lib/tmpfiles.d/handtrack.conf etc/handtrack/handtrackd.toml \
         lib/python3/dist-packages/handtrack/__init__.py share/handtrack/examples/CMakeLists.txt \
         share/handtrack/examples/pinch_click.cpp share/handtrack/examples/handtrack_print_poses.py \
         share/doc/handtrack/SERVICE.md; do
  [ -e "$prefix/$f" ] || fail "$f not installed"
done
libdir="$(dirname "$(find "$prefix" -name 'libhandtrack_client.so.2' | head -n1)")"
[ -f "$libdir/cmake/handtrack/handtrackConfig.cmake" ] || fail "no CMake package in $libdir"
[ -f "$libdir/pkgconfig/handtrack.pc" ] || fail "no pkg-config file in $libdir"
grep -qx "ExecStart=$prefix/sbin/handtrackd --config $prefix/etc/handtrack/handtrackd.toml" \
  "$prefix/lib/systemd/system/handtrackd.service" || fail "ExecStart does not point into the prefix"
# The installed configuration is the daemon's defaults.
diff <("$prefix/sbin/handtrackd" --print-config) "$prefix/etc/handtrack/handtrackd.toml" \
  || fail "installed handtrackd.toml differs from handtrackd --print-config"
echo "layout ok ($((SECONDS - t0)) s)"

# find_package(handtrack): the examples' own CMakeLists.txt, with warnings as errors.
cmake -S "$prefix/share/handtrack/examples" -B "$work/build" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS="-Wall -Wextra -Werror" \
  -DCMAKE_CXX_FLAGS="-Wall -Wextra -Werror" > "$work/configure.log"
cmake --build "$work/build" -j2 > "$work/build.log" || { cat "$work/build.log"; fail "find_package build"; }
# pkg-config, the way a Makefile builds them.
export PKG_CONFIG_PATH="$libdir/pkgconfig"
ex="$prefix/share/handtrack/examples"
cc -std=c11 -Wall -Wextra -Werror "$ex/print_poses.c" $(pkg-config --cflags --libs handtrack) -o "$work/pc_print_poses_c"
c++ -std=c++17 -Wall -Wextra -Werror "$ex/print_poses.cpp" $(pkg-config --cflags --libs handtrack) -o "$work/pc_print_poses_cpp"
c++ -std=c++17 -Wall -Wextra -Werror "$ex/pinch_click.cpp" $(pkg-config --cflags --libs handtrack) -o "$work/pc_pinch_click"
echo "examples built with find_package and pkg-config ($((SECONDS - t0)) s)"

# The installed daemon, its installed configuration, the synthetic pinch motion.
name="htsvc_clients_$$"
"$prefix/sbin/handtrackd" --config "$prefix/etc/handtrack/handtrackd.toml" --source synthetic:pinch \
  --shm-name "$name" --log-level warn > "$work/handtrackd.log" 2>&1 &
daemon=$!
cleanup() { kill "$daemon" 2>/dev/null || true; wait "$daemon" 2>/dev/null || true; rm -f "/dev/shm/$name"; }
trap cleanup EXIT
export LD_LIBRARY_PATH="$libdir"
"$prefix/bin/handtrack-cat" --shm-name "$name" --count 1 --timeout 20 > /dev/null || fail "no pose from the installed handtrackd"

# "frame N (missed M): hand ID HANDEDNESS STATE index tip X Y Z mm ...[; hand ...]" or
# "frame N (missed M): no hand" lines: COUNT of them, frames increasing, a tracked hand (the
# synthetic camera's right hand) somewhere in the working volume (150-600 mm, docs/TRACKER.md).
check_lines() {
  local file="$1" count="$2"
  python3 - "$file" "$count" <<'PY'
import re, sys
lines = open(sys.argv[1]).read().splitlines()
want = int(sys.argv[2])
frame_pat = re.compile(r"^frame (\d+) \(missed \d+\): (.*)$")
hand_pat = re.compile(r"^hand ([1-9]\d*) (left|right) (tracking|recovering) index tip "
                      r"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) mm")
frames, tracked = [], 0
for line in lines:
    m = frame_pat.match(line)
    if not m:
        sys.exit(f"FAIL: {sys.argv[1]}: unexpected line '{line}'")
    frames.append(int(m.group(1)))
    if m.group(2) == "no hand":
        continue
    for part in m.group(2).split("; "):
        h = hand_pat.match(part)
        if not h:
            sys.exit(f"FAIL: {sys.argv[1]}: unexpected hand '{part}' in '{line}'")
        if h.group(3) == "tracking" and h.group(2) == "right":
            tracked += 1
            if not 100.0 <= float(h.group(6)) <= 700.0:
                sys.exit(f"FAIL: {sys.argv[1]}: index tip depth {h.group(6)} mm outside the working volume")
if len(lines) != want:
    sys.exit(f"FAIL: {sys.argv[1]}: {len(lines)} lines, expected {want}")
if frames != sorted(set(frames)):
    sys.exit(f"FAIL: {sys.argv[1]}: frames not increasing: {frames}")
if tracked == 0:
    sys.exit(f"FAIL: {sys.argv[1]}: no tracked right hand")
print(f"{sys.argv[1]}: {want} frames, frames {frames[0]}..{frames[-1]}, {tracked} tracked right hands")
PY
}
timeout 30 "$work/build/print_poses_c" "$name" 20 > "$work/c.txt" || fail "C example (find_package)"
check_lines "$work/c.txt" 20
timeout 30 "$work/pc_print_poses_c" "$name" 20 > "$work/c_pc.txt" || fail "C example (pkg-config)"
check_lines "$work/c_pc.txt" 20
timeout 30 "$work/build/print_poses_cpp" "$name" 20 > "$work/cpp.txt" || fail "C++ example (find_package)"
check_lines "$work/cpp.txt" 20
timeout 30 "$work/pc_print_poses_cpp" "$name" 20 > "$work/cpp_pc.txt" || fail "C++ example (pkg-config)"
check_lines "$work/cpp_pc.txt" 20
PYTHONPATH="$prefix/lib/python3/dist-packages" PYTHONDONTWRITEBYTECODE=1 timeout 30 \
  python3 "$ex/handtrack_print_poses.py" --shm-name "$name" --count 20 > "$work/py.txt" || fail "Python example"
check_lines "$work/py.txt" 20

# Pinch to click: the synthetic pinch closes and opens the hand again and again, so each hand's
# events come as start/end pairs, in frame order, at a position in the working volume.
timeout 90 "$work/build/pinch_click" --shm-name "$name" --events 4 --timeout 20 > "$work/events.txt" \
  || { cat "$work/events.txt"; fail "pinch_click"; }
timeout 90 "$work/pc_pinch_click" --shm-name "$name" --events 2 --timeout 20 > "$work/events_pc.txt" \
  || fail "pinch_click (pkg-config)"
python3 - "$work/events.txt" "$work/events_pc.txt" <<'PY'
import json, sys
for path in sys.argv[1:]:
    events = [json.loads(line) for line in open(path)]
    kinds = [e["event"] for e in events]
    if len(events) < 2:
        sys.exit(f"FAIL: {path}: events {kinds}")
    for hand_id in {e["hand_id"] for e in events}:
        mine = [e["event"] for e in events if e["hand_id"] == hand_id]
        if mine != ["pinch_start", "pinch_end"] * (len(mine) // 2) + ["pinch_start"] * (len(mine) % 2):
            sys.exit(f"FAIL: {path}: hand {hand_id}: events {mine}, expected alternating start/end")
    if any(not e["hand_id"] > 0 or e["handedness"] not in ("left", "right") for e in events):
        sys.exit(f"FAIL: {path}: events without a hand id or handedness: {events}")
    frames = [e["frame"] for e in events]
    if frames != sorted(frames) or len(set(frames)) != len(frames):
        sys.exit(f"FAIL: {path}: frames not increasing: {frames}")
    for e in events:
        x, y, z = e["position_mm"]
        if e.get("reason") != "hand_lost" and not 100.0 <= z <= 700.0:
            sys.exit(f"FAIL: {path}: position {e['position_mm']} outside the working volume")
        # The library's hysteresis (HANDTRACK_GESTURE_ON/OFF), give or take the printed rounding.
        if e["event"] == "pinch_start" and not e["strength"] >= 0.7995:
            sys.exit(f"FAIL: {path}: pinch_start without a closed pinch: {e}")
        if e["event"] == "pinch_end" and e["reason"] == "released" and not e["strength"] <= 0.5005:
            sys.exit(f"FAIL: {path}: pinch_end without an open pinch: {e}")
        if e["event"] == "pinch_end" and not e["duration_ms"] > 0.0:
            sys.exit(f"FAIL: {path}: pinch_end duration {e['duration_ms']}")
    print(f"{path}: {kinds}")
PY
echo "installed clients ok ($((SECONDS - t0)) s)"
