#!/usr/bin/env bash
# LinuxCNC's standalone G-code interpreter `rs274` as an independent reader of
# our programs (crates/post). Debian's linuxcnc-uspace is fetched with
# `apt-get download` and unpacked with `dpkg-deb -x` into a cache folder:
# nothing is installed, no post-install script runs.
#
#   bash tools/peers/linuxcnc/setup.sh      # into $HOME/.cache/thinplan-linuxcnc
#
# rs274 needs the package's own libraries (librs274, libnml, liblinuxcnchal,
# liblinuxcncini, libpyplugin, libtooldata: all in linuxcnc-uspace) and
# boost-python; the script fetches the few libraries `ldd` still misses from
# the packages that ship them, and fails loudly on any it does not know.
# Takes a few seconds (a 21 MB download); needs `apt-get update` done once.
set -euo pipefail
DEST="${THINPLAN_LINUXCNC:-$HOME/.cache/thinplan-linuxcnc}"
mkdir -p "$DEST/debs"
cd "$DEST/debs"

fetch() { # package name
  if ! ls "$1"_*.deb >/dev/null 2>&1; then
    # Downloading into a root-owned folder: no _apt sandbox to drop to.
    apt-get -o APT::Sandbox::User=root download "$1" >/dev/null
  fi
  dpkg-deb -x "$1"_*.deb "$DEST"
}

fetch linuxcnc-uspace
export LD_LIBRARY_PATH="$DEST/usr/lib:$DEST/usr/lib/x86_64-linux-gnu"
RS274="$DEST/usr/bin/rs274"
test -x "$RS274"

# Library file → the Debian (bookworm) package that ships it.
declare -A SHIPS=(
  [libboost_python311.so.1.74.0]=libboost-python1.74.0
  [libpython3.11.so.1.0]=libpython3.11
  [libtirpc.so.3]=libtirpc3
  [libgssapi_krb5.so.2]=libgssapi-krb5-2
  [libkrb5.so.3]=libkrb5-3
  [libk5crypto.so.3]=libk5crypto3
  [libkrb5support.so.0]=libkrb5support0
  [libkeyutils.so.1]=libkeyutils1
  [libcom_err.so.2]=libcom-err2
  [libudev.so.1]=libudev1
  [libexpat.so.1]=libexpat1
  [libz.so.1]=zlib1g
)
for _ in 1 2 3; do
  missing=$(ldd "$RS274" | awk '/not found/ {print $1}')
  [ -z "$missing" ] && break
  for lib in $missing; do
    pkg="${SHIPS[$lib]:-}"
    if [ -z "$pkg" ]; then
      echo "rs274 needs $lib and this script does not know which package ships it" >&2
      exit 1
    fi
    fetch "$pkg"
  done
done
missing=$(ldd "$RS274" | grep "not found" || true)
if [ -n "$missing" ]; then
  echo "rs274 still has unresolved libraries:" >&2
  echo "$missing" >&2
  exit 1
fi
# A one-line program proves it runs.
tmp=$(mktemp -d)
printf 'G21 G90\nG1 X1 F100\nM2\n' > "$tmp/t.ngc"
printf 'T1 P1 D6.000 Z0.000 ;test\n' > "$tmp/t.tbl"
"$RS274" -t "$tmp/t.tbl" -g "$tmp/t.ngc" </dev/null 2>/dev/null | grep -q "STRAIGHT_FEED(1.0000"
rm -rf "$tmp"
echo "rs274 OK: $RS274"
