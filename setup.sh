#!/usr/bin/env bash
# Install what fem_forms needs on Debian 12 and make a venv (.venv) that sees Debian's FEniCSx stack
# (and Sphinx, MyST and the furo theme for the manual in docs/).
# Idempotent: a second run installs nothing and takes a second.
set -euo pipefail
cd "$(dirname "$0")"
# clang: FFCx's large forms compile 4.6x faster with it than with gcc (fem_forms/logs.py, FAST_CC); npm fetches
# three.js (below); chromium (headless) only for the test suite, which opens report.html in a real browser
pkgs="python3-dolfinx python3-dolfinx-real python3-ufl python3-petsc4py python3-slepc4py python3-gmsh
python3-meshio python3-pytest python3-mpi4py openmpi-bin libopenblas0-pthread python3-matplotlib
python3-scipy python3-pil python3-jsonschema python3-venv python3-setuptools python3-pip python3-pytest-xdist
python3-sphinx python3-myst-parser furo clang chromium fonts-dejavu-core"
# npm (to fetch three.js, below): Debian's, unless the machine has one already (Node.js from elsewhere ships its own)
command -v npm >/dev/null 2>&1 || pkgs="$pkgs npm"
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "setup: installing$missing"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
if [ ! -x .venv/bin/fem-forms ]; then
  /usr/bin/python3 -m venv --system-site-packages .venv
  .venv/bin/python -m pip install -q --no-build-isolation --no-deps -e . >/dev/null
fi
# pymeshfix (MeshFix: [mesh] repair = true) from the package index; a 1.4 MB wheel, uses Debian's numpy
if ! .venv/bin/python -c "import pymeshfix" 2>/dev/null; then
  .venv/bin/python -m pip install -q --no-warn-script-location "pymeshfix>=0.17" >/dev/null 2>&1 \
    || { echo "setup: pip could not install pymeshfix" >&2; exit 1; }
fi
# ipctk (the IPC Toolkit: contact barrier, collision candidates, CCD) from the package index; a wheel for 3.11
if ! .venv/bin/python -c "import ipctk" 2>/dev/null; then
  .venv/bin/python -m pip install -q --no-warn-script-location "ipctk>=1.6,<2" >/dev/null 2>&1 \
    || { echo "setup: pip could not install ipctk" >&2; exit 1; }
fi
# three.js, report.html's 3D viewer (embedded into each page as it is written), from the npm registry: the 4.8 MB
# package, of which three files (2.1 MB) and its licence are kept in the venv; none of it is in the repository
THREE_VERSION=0.187.0
THREE_DIR=.venv/share/fem_forms/three
if [ ! -f "$THREE_DIR/OrbitControls.js" ] || ! grep -q "$THREE_VERSION" "$THREE_DIR/VERSION" 2>/dev/null; then
  tmp=$(mktemp -d)
  (cd "$tmp" && npm pack --silent "three@$THREE_VERSION" >/dev/null 2>&1) \
    || { echo "setup: npm could not fetch three.js" >&2; exit 1; }
  tar xzf "$tmp/three-$THREE_VERSION.tgz" -C "$tmp" package/build/three.module.js package/build/three.core.js \
    package/examples/jsm/controls/OrbitControls.js package/LICENSE
  mkdir -p "$THREE_DIR"
  cp "$tmp"/package/build/three.module.js "$tmp"/package/build/three.core.js \
    "$tmp"/package/examples/jsm/controls/OrbitControls.js "$tmp"/package/LICENSE "$THREE_DIR"/
  echo "$THREE_VERSION" > "$THREE_DIR/VERSION"
  rm -rf "$tmp"
fi
# byte-compile the package as a regular pip install would (an editable one does not; with
# PYTHONDONTWRITEBYTECODE set, every run would compile ~100 modules from source: 0.1 s, measured)
.venv/bin/python -m compileall -q fem_forms >/dev/null
echo "setup: ready ($(.venv/bin/python -c 'import dolfinx; print("dolfinx", dolfinx.__version__)'))"
