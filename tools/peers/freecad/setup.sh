#!/usr/bin/env bash
# Fetch Debian's FreeCAD Python library (for `import area`, FreeCAD's libarea with Adaptive2d)
# without installing it system-wide: apt-get download + dpkg-deb -x into a cache folder.
#
# area.so needs only libarea-native.so (same package), libpython3.11 and the C/C++ runtime:
# `ldd` shows nothing else, so none of the package's declared dependencies (Qt, OCCT, VTK …)
# has to be fetched. The script checks this and fails loudly if it ever changes.
set -euo pipefail
DEST="${THINPLAN_FREECAD:-$HOME/.cache/thinplan-freecad}"
PKG=libfreecad-python3-0.20
mkdir -p "$DEST/debs"
cd "$DEST/debs"
if ! ls ${PKG}_*.deb >/dev/null 2>&1; then
  apt-get download "$PKG"
fi
dpkg-deb -x ${PKG}_*.deb "$DEST"
LIB="$DEST/usr/lib/freecad-python3/lib"
test -f "$LIB/area.so"
missing=$(LD_LIBRARY_PATH="$LIB" ldd "$LIB/area.so" | grep "not found" || true)
if [ -n "$missing" ]; then
  echo "area.so has unresolved libraries:" >&2
  echo "$missing" >&2
  exit 1
fi
PY=${PYTHON:-python3}
LD_LIBRARY_PATH="$LIB" "$PY" -c "import sys; sys.path.insert(0, '$LIB'); import area; area.Adaptive2d(); print('FreeCAD area.Adaptive2d OK:', area.__file__)"
