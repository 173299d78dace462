#!/usr/bin/env bash
# scripts/lib/job-pool.sh: a command that fails fails the script, whether the pool had to wait for it
# to make room or it ended on its own before pool_finish; commands that succeed let it go on.
#   job_pool_test.sh POOL_SH
pool="$1"
failures=0
run() {  # JOBS, then the script's body after pool_start; prints its exit code
  bash -c "set -euo pipefail; source '$pool'; HANDTRACK_JOBS=$1; pool_start; $2" >/dev/null 2>&1
  echo $?
}
check() {  # WHAT EXPECTED ACTUAL
  if [ "$2" != "$3" ]; then
    echo "FAILED: $1: exit $3, expected $2"
    failures=$((failures + 1))
  fi
}
check "all succeed" 0 "$(run 2 'for i in 1 2 3 4; do pool_run true; done; pool_finish')"
check "a failure the pool waits for to make room" 3 \
  "$(run 1 "pool_run sh -c 'exit 3'; pool_run true; pool_finish")"
check "a failure that ends before pool_finish, the pool never full" 3 \
  "$(run 3 "pool_run sh -c 'exit 3'; sleep 0.3; pool_run true; pool_finish")"
check "a bad HANDTRACK_JOBS" 1 "$(run x 'true')"
exit $((failures > 0))
