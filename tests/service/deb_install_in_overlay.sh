#!/usr/bin/env bash
# Helper of deb_package.sh, run inside `unshare -m`: / as the lower layer of an overlay whose
# upper layer is a tmpfs, chroot into it, dpkg -i, checks, dpkg --purge, leftover checks.
#   deb_install_in_overlay.sh DEB WORK_DIR
set -euo pipefail
deb="$1" work="$2"
fail() { echo "FAIL: $*"; exit 1; }
t="$work/overlay"
mkdir -p "$t"
mount -t tmpfs tmpfs "$t"
mkdir -p "$t/upper" "$t/work" "$t/root"
mount -t overlay overlay -o "lowerdir=/,upperdir=$t/upper,workdir=$t/work" "$t/root"
r="$t/root"
mount --bind /proc "$r/proc"
mount --bind /dev "$r/dev"
mount -t tmpfs tmpfs "$r/dev/shm"       # the host's rings are not the package's business
mount -t tmpfs tmpfs "$r/run"           # no systemd, no udev running in the chroot
mount -t tmpfs tmpfs "$r/tmp"
in_root() { chroot "$r" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin "$@"; }

cp "$deb" "$r/tmp/"                      # the chroot's /tmp is a fresh tmpfs
in_root dpkg -i "/tmp/$(basename "$deb")" > "$work/dpkg-install.log" 2>&1 || { cat "$work/dpkg-install.log"; fail "dpkg -i"; }
in_root dpkg -L handtrack | sort > "$work/dpkg-L.txt"
echo "dpkg -i ok: $(wc -l < "$work/dpkg-L.txt") paths"

# What the maintainer scripts did.
in_root getent passwd handtrack > /dev/null || fail "postinst did not create user handtrack"
in_root getent group handtrack > /dev/null || fail "postinst did not create group handtrack"
[ "$(in_root stat -c '%a %U %G' /var/lib/handtrack)" = "750 handtrack handtrack" ] \
  || fail "/var/lib/handtrack: $(in_root stat -c '%a %U %G' /var/lib/handtrack)"
[ "$(in_root systemctl is-enabled handtrackd.service 2>/dev/null)" = enabled ] || fail "handtrackd.service not enabled"
cache="$(in_root ldconfig -p)"   # not piped into grep -q: with pipefail, SIGPIPE would fail it
grep -q 'libhandtrack_client.so.2 ' <<< "$cache" || fail "libhandtrack_client.so.2 not in the linker cache"
out="$(in_root systemd-analyze verify /usr/lib/systemd/system/handtrackd.service 2>&1)" \
  || { echo "$out"; fail "systemd-analyze verify of the installed unit"; }
[ -z "$out" ] || { echo "$out"; fail "systemd-analyze verify warns about the installed unit"; }
in_root sh -c 'handtrackd --print-config | diff - /etc/handtrack/handtrackd.toml' > /dev/null \
  || fail "the installed configuration differs from the daemon's defaults"
# The installed daemon as the service's user: the ring it creates is handtrack:handtrack 0640.
in_root setpriv --reuid=handtrack --regid=handtrack --clear-groups \
  handtrackd --source synthetic:pinch --fast --frames 20 --log-level warn > /dev/null \
  || fail "handtrackd as user handtrack"
[ "$(in_root stat -c '%a %U %G' /dev/shm/handtrack)" = "640 handtrack handtrack" ] \
  || fail "ring: $(in_root stat -c '%a %U %G' /dev/shm/handtrack)"
# An .oni recording plays through the installed helper process (when the workspace has one).
recording="${HANDTRACK_ONI_RECORDING:-}"
if [ -n "$recording" ] && [ -f "$recording" ]; then
  cp "$recording" "$r/tmp/recording.oni"
  in_root setpriv --reuid=handtrack --regid=handtrack --clear-groups \
    handtrackd --source oni:/tmp/recording.oni --fast --shm-name handtrack-oni --log-level warn > /dev/null \
    || fail "handtrackd playing an .oni recording through /usr/libexec/handtrack/handtrack-source-helper"
  echo "an .oni recording played through the installed source helper"
fi
# Python (as root, so it may leave bytecode next to the module: prerm must clean that up), and the
# browser bridge, both from the package, against the package's daemon.
in_root python3 -c 'import handtrack; print("python module", handtrack.__file__)'
in_root sh -c 'handtrackd --source synthetic:pinch --shm-name handtrack-live --log-level warn > /tmp/live.log 2>&1 &
  daemon=$!
  handtrack-ws --shm-name handtrack-live --port 0 > /tmp/ws.out 2>&1 &
  bridge=$!
  timeout 60 python3 - <<"PY"
import re, time, urllib.request
import handtrack
client = handtrack.Client.wait_for("handtrack-live", timeout=20)
deadline = time.monotonic() + 20
frames = [f for _, f in zip(range(3), client.frames(timeout=10))]
assert len(frames) == 3 and all(h.handedness in ("left", "right") for f in frames for h in f.hands), frames
print("python module read", len(frames), "frames from the installed daemon")
while not re.search(r":([0-9]+)/", open("/tmp/ws.out").read()):
    assert time.monotonic() < deadline, open("/tmp/ws.out").read()
    time.sleep(0.1)
port = re.search(r":([0-9]+)/", open("/tmp/ws.out").read()).group(1)
page = urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10).read().decode()
assert "<canvas" in page, page[:200]
print("handtrack-ws served its page on port", port)
PY
  status=$?; kill $daemon $bridge 2>/dev/null; wait; exit $status' || fail "the installed Python module and handtrack-ws against the installed daemon"
echo "installed package ok"

# An edited conffile survives remove and goes with purge.
echo "# local edit" >> "$r/etc/handtrack/handtrackd.toml"
in_root dpkg --remove handtrack > "$work/dpkg-remove.log" 2>&1 || { cat "$work/dpkg-remove.log"; fail "dpkg --remove"; }
[ -f "$r/etc/handtrack/handtrackd.toml" ] || fail "dpkg --remove removed the edited conffile"
[ ! -e "$r/dev/shm/handtrack" ] || fail "postrm left the stopped ring"
in_root dpkg --purge handtrack > "$work/dpkg-purge.log" 2>&1 || { cat "$work/dpkg-purge.log"; fail "dpkg --purge"; }
if grep -q 'warning' "$work/dpkg-remove.log" "$work/dpkg-purge.log"; then
  cat "$work/dpkg-remove.log" "$work/dpkg-purge.log"; fail "dpkg warned while removing"
fi
in_root dpkg-query -W handtrack >/dev/null 2>&1 && fail "still installed after purge"

# dpkg -L before vs after: every path the package had is gone, unless the machine had it before
# (shared directories such as /usr/lib).
left=0
while read -r p; do
  [ -n "$p" ] || continue
  if [ -e "$r$p" ] || [ -L "$r$p" ]; then
    if [ -e "$p" ] || [ -L "$p" ]; then continue; fi
    echo "left behind: $p"; left=1
  fi
done < "$work/dpkg-L.txt"
# Anything else new in the upper layer, beyond the databases dpkg, ldconfig and the user
# management keep (the system user stays on purge, as Debian does).
(cd "$t/upper" && find . -mindepth 1 | sed 's#^\.##') | sort > "$work/upper.txt"
while read -r p; do
  case "$p" in
    /var/lib/dpkg|/var/lib/dpkg/*|/var/log|/var/log/*|/var/cache|/var/cache/ldconfig*) continue ;;
    /etc/passwd*|/etc/group*|/etc/shadow*|/etc/gshadow*|/etc/subuid*|/etc/subgid*|/etc/ld.so.cache|/etc/.pwd.lock) continue ;;
  esac
  if [ -c "$t/upper$p" ]; then continue; fi                      # whiteout: something removed
  if [ -d "$t/upper$p" ] && [ -d "$p" ]; then continue; fi      # a copied-up existing directory
  echo "left behind (not in dpkg -L): $p"; left=1
done < "$work/upper.txt"
[ "$left" = 0 ] || fail "the purge left files behind"
echo "purge ok: nothing left behind (user handtrack stays, as Debian keeps system users)"
