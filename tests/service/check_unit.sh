#!/usr/bin/env bash
# handtrackd.service and handtrack-ws.service: `systemd-analyze verify` is clean and
# `systemd-analyze security --offline` scores 2.0 or better (lower is better) for both; the things
# the ring needs are still there.
#   check_unit.sh SOURCE_DIR HANDTRACKD HANDTRACK_WS WORK_DIR
set -euo pipefail
src="$1" handtrackd="$2" ws="$3" work="$4"
rm -rf "$work" && mkdir -p "$work"
[ "$(basename "$handtrackd")" = handtrackd ] || { echo "FAIL: $handtrackd is not handtrackd"; exit 1; }
[ "$(basename "$ws")" = handtrack-ws ] || { echo "FAIL: $ws is not handtrack-ws"; exit 1; }

# A unit as `cmake --install` writes it (install_service_files.cmake), pointing at the built
# programs so verify finds them: the shared sandbox pasted in, the paths filled in.
render() {
  awk -v inc="$src/systemd/sandbox.inc" '
    $0 == "@HANDTRACK_SANDBOX@" { while ((getline line < inc) > 0) print line; next } { print }' "$1" |
  sed -e "s#@HANDTRACK_SBINDIR@#$(dirname "$handtrackd")#g" \
      -e "s#@HANDTRACK_BINDIR@#$(dirname "$ws")#g" \
      -e "s#@HANDTRACK_CONFDIR@#$src/data#g" \
      -e "s#@HANDTRACK_DOCDIR@#$src/docs#g" > "$2"
}

# verify and security score of one rendered unit
check() {
  local unit="$1" name
  name="$(basename "$unit")"
  grep -q '@HANDTRACK_' "$unit" && { grep '@HANDTRACK_' "$unit"; echo "FAIL: $name: placeholders left"; exit 1; }
  out="$(systemd-analyze verify "$unit" 2>&1)" || { echo "$out"; echo "FAIL: $name: systemd-analyze verify"; exit 1; }
  if [ -n "$out" ]; then echo "$out"; echo "FAIL: $name: systemd-analyze verify printed warnings"; exit 1; fi
  echo "$name: systemd-analyze verify: clean"
  sec="$(systemd-analyze security --offline=true --no-pager "$unit" 2>&1)" || true
  score="$(printf '%s\n' "$sec" | sed -n "s/.*Overall exposure level for $name: \([0-9.]*\).*/\1/p")"
  if [ -z "$score" ]; then printf '%s\n' "$sec"; echo "FAIL: $name: no exposure level in the output"; exit 1; fi
  printf '%s\n' "$sec" | grep '✗' || true
  echo "$name: security exposure: $score (must be <= 2.0)"
  awk -v s="$score" 'BEGIN { exit !(s <= 2.0) }' || { echo "FAIL: $name: exposure $score > 2.0"; exit 1; }
}

unit="$work/handtrackd.service"
render "$src/systemd/handtrackd.service.in" "$unit"
check "$unit"
ws_unit="$work/handtrack-ws.service"
render "$src/systemd/handtrack-ws.service.in" "$ws_unit"
check "$ws_unit"
grep -qx 'RemoveIPC=no' "$ws_unit" || { echo "FAIL: handtrack-ws.service would remove the ring (RemoveIPC)"; exit 1; }
grep -qx 'IPAddressAllow=localhost' "$ws_unit" || { echo "FAIL: handtrack-ws.service is not limited to localhost"; exit 1; }

# What the service needs must survive later "hardening": the segment lives in the host's
# /dev/shm and outlives the daemon, the daemon's user is not dynamic, the camera stays reachable.
need() { grep -qx "$1" "$unit" || { echo "FAIL: the unit lacks '$1'"; exit 1; }; }
never() { if grep -Eq "$1" "$unit"; then echo "FAIL: the unit must not have $2"; exit 1; fi; }
need 'Type=notify'
need 'NotifyAccess=main'
need 'RemoveIPC=no'
need 'User=handtrack'
need 'Group=handtrack'
need 'DevicePolicy=closed'
need 'DeviceAllow=char-usb_device rw'
need 'RestrictAddressFamilies=AF_UNIX AF_NETLINK'
need 'IPAddressDeny=any'
grep -Eq '^WatchdogSec=[1-9]' "$unit" || { echo "FAIL: no WatchdogSec"; exit 1; }
grep -Eq '^StartLimitBurst=[1-9]' "$unit" || { echo "FAIL: no start limit"; exit 1; }
never '^PrivateIPC=(yes|true|1|on)' 'PrivateIPC= (clients would not see the ring)'
never '^DynamicUser=(yes|true|1|on)' 'DynamicUser= (removes the ring when the service stops)'
never '^PrivateDevices=(yes|true|1|on)' 'PrivateDevices= (hides /dev/bus/usb)'
never '^(TemporaryFileSystem|InaccessiblePaths|BindPaths|BindReadOnlyPaths)=.*/dev/shm' 'a private /dev/shm'
never '^PrivateNetwork=(yes|true|1|on)' 'PrivateNetwork= (no udev hotplug events)'
echo "unit ok"
