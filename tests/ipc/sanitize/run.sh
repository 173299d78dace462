#!/usr/bin/env bash
# Sanitizer jobs for ipc, run by ctest (tests/ipc/CMakeLists.txt):
#   run.sh build DIR        configure (clang) and build the sanitizer targets in DIR
#   run.sh tsan DIR         the in-process unit tests under TSan
#   run.sh fuzz DIR SECS    the header/client fuzzer for SECS seconds from a valid seed
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
job="$1" dir="$2"
case "$job" in
  build)
    if [ ! -f "$dir/CMakeCache.txt" ]; then
      CC=clang CXX=clang++ cmake -S "$here" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
    fi
    cmake --build "$dir" -j"${HANDTRACK_JOBS:-2}" ;;
  tsan)
    # Timing assertions (wake-up within N ms) are for the plain build; TSan slows code 5-15x.
    TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" "$dir/ipc_unit_test_tsan" \
      --gtest_filter='IpcConcurrency.*:IpcRing.*:IpcRestart.NewWriter*:IpcCApi.*:IpcValidate.*:IpcOpen.*:IpcOwnership.*:IpcLiveness.StatsAndState*'
    ;;
  fuzz)
    secs="${3:-20}"
    corpus="$dir/corpus"
    mkdir -p "$corpus"
    "$dir/ipc_fuzz_seed" "$corpus/valid_segment"
    "$dir/ipc_fuzz_header" -max_total_time="$secs" -max_len=8192 -print_final_stats=1 \
      -artifact_prefix="$dir/" "$corpus" 2>&1 | tail -n 25 ;;
  *) echo "run.sh: unknown job $job" >&2; exit 2 ;;
esac
