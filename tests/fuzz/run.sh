#!/usr/bin/env bash
# The file-reader fuzzers (tests/fuzz/CMakeLists.txt), for ctest and scripts/fuzz:
#   run.sh build SRC DIR          configure (once, clang, HANDTRACK_SANITIZE=fuzz) and build them
#   run.sh run DIR TARGET SECS    run TARGET for SECS seconds from its checked-in corpus; any
#                                 finding (crash, leak, UB, an allocation over 256 MB, a 10 s
#                                 input) fails, leaving the input in DIR/artifacts/
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
job="$1"
case "$job" in
  build)
    src="$2" dir="$3"
    if [ ! -f "$dir/CMakeCache.txt" ]; then
      # A unity build with line tables only (-g1, enough for the sanitizers' stacks).
      CC=clang CXX=clang++ cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DHANDTRACK_SANITIZE=fuzz -DHANDTRACK_WERROR=OFF -DCMAKE_UNITY_BUILD=ON \
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" >/dev/null
    fi
    cmake --build "$dir" -j"${HANDTRACK_JOBS:-2}" --target \
      fuzz_png fuzz_camera_json fuzz_sequence_csv fuzz_config fuzz_forest ;;
  run)
    dir="$2" target="$3" secs="$4"
    # New inputs go to a working corpus in the build tree; the checked-in seeds stay as they are.
    work="$dir/corpus/$target"
    mkdir -p "$work" "$dir/artifacts"
    # The largest frame a PNG may claim is 8192 x 8192 x 2 bytes = 128 MB: more is a finding.
    "$dir/tests/fuzz/$target" -max_total_time="$secs" -malloc_limit_mb=256 -rss_limit_mb=2048 \
      -timeout=10 -max_len=16384 -print_final_stats=1 -artifact_prefix="$dir/artifacts/$target-" \
      "$work" "$here/corpus/$target" > "$dir/$target.log" 2>&1 || {
        tail -n 60 "$dir/$target.log"; exit 1; }
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$dir/$target.log")
    echo "$target: ${runs:-?} executions in $secs s, no finding" ;;
  *) echo "run.sh: unknown job $job" >&2; exit 2 ;;
esac
