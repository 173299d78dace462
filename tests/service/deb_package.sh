#!/usr/bin/env bash
# The Debian package: cpack builds it; its files sit in FHS places, the configuration is a
# conffile, the maintainer scripts are there. As root it is then installed with dpkg -i and
# purged with dpkg --purge inside an overlay of / (a private mount namespace: the machine is not
# touched), with its maintainer scripts really running (systemd-sysusers, tmpfiles, enable);
# after the purge nothing the package or its scripts made may be left (dpkg -L before vs after,
# and every new file in the overlay's upper layer).
#   deb_package.sh BUILD_DIR WORK_DIR SOURCE_DIR          (exit 77: install part skipped)
set -euo pipefail
build="$1" work="$2" src="$3"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rm -rf "$work" && mkdir -p "$work/out"
fail() { echo "FAIL: $*"; exit 1; }
t0=$SECONDS

(cd "$work" && cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/out") > "$work/cpack.log" 2>&1 \
  || { cat "$work/cpack.log"; fail "cpack"; }
deb="$(ls "$work"/out/*.deb)"
echo "built $(basename "$deb") ($(du -k "$deb" | cut -f1) KiB, $((SECONDS - t0)) s)"

dpkg-deb -c "$deb" | awk '{print $6}' | sed 's#^\./#/#; s#/$##' > "$work/contents.txt"
has() { grep -Eqx "$1" "$work/contents.txt" || fail "the package lacks $1"; }
has /usr/sbin/handtrackd
has /usr/libexec/handtrack/handtrack-source-helper
has /usr/bin/handtrack-cat
has /usr/bin/handtrack-ws
has /usr/lib/systemd/system/handtrack-ws.service
has /usr/lib/systemd/system/handtrackd.service
has /usr/lib/udev/rules.d/59-handtrack-cameras.rules
has /usr/lib/sysusers.d/handtrack.conf
has /usr/lib/tmpfiles.d/handtrack.conf
has /etc/handtrack/handtrackd.toml
has /usr/include/handtrack/client.h
has '/usr/lib(/[a-z0-9_-]+)?/libhandtrack_client.so.2'
has '/usr/lib(/[a-z0-9_-]+)?/cmake/handtrack/handtrackConfig.cmake'
has '/usr/lib(/[a-z0-9_-]+)?/pkgconfig/handtrack.pc'
has /usr/lib/python3/dist-packages/handtrack/__init__.py
has /usr/share/handtrack/examples/pinch_click.cpp
has /usr/share/doc/handtrack/SERVICE.md
if [ -f "$src/data/part_forest.htf" ]; then has /usr/share/handtrack/part_forest.htf; fi
if grep -Eq '^/usr/(local|etc)(/|$)|^/home|^/root|^/work' "$work/contents.txt"; then
  fail "files outside FHS places: $(grep -E '^/usr/(local|etc)(/|$)|^/home|^/root|^/work' "$work/contents.txt" | head -3)"
fi
dpkg-deb -e "$deb" "$work/control"
grep -qx /etc/handtrack/handtrackd.toml "$work/control/conffiles" || fail "handtrackd.toml is not a conffile"
for script in postinst prerm postrm; do
  [ -x "$work/control/$script" ] || fail "no $script"
  sh -n "$work/control/$script" || fail "$script: syntax"
done
dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/lib/systemd/system/handtrackd.service > "$work/unit"
grep -qx 'ExecStart=/usr/sbin/handtrackd --config /etc/handtrack/handtrackd.toml' "$work/unit" \
  || fail "ExecStart: $(grep ExecStart= "$work/unit")"
dpkg-deb -f "$deb" Depends
echo "package contents ok"

if [ "$(id -u)" != 0 ]; then echo "not root: dpkg -i / --purge skipped"; exit 77; fi
if ! grep -qw overlay /proc/filesystems || ! unshare -m true 2>/dev/null; then
  echo "no overlayfs or mount namespaces here: dpkg -i / --purge skipped"; exit 77
fi
if dpkg-query -W -f='${Status}' handtrack 2>/dev/null | grep -q 'ok installed'; then
  echo "handtrack is installed on this machine: the scratch install would be an upgrade; skipped"; exit 77
fi
# The install/purge runs in a private mount namespace (the overlay vanishes with it); its
# results come back through the files it writes to $work.
unshare -m --propagation private "$here/deb_install_in_overlay.sh" "$deb" "$work" \
  || fail "install/purge in the overlay root"
echo "deb package ok ($((SECONDS - t0)) s)"
