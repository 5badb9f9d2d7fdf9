#!/bin/sh
# Install the Debian 12 packages pd needs, when some are missing; packages
# given as arguments are needed too (make fuzz: clang and its libFuzzer).
# Run as root (CI and `make check`/`make demo` on a fresh machine); as another
# user it only reports what is missing.
set -e
pkgs="build-essential pkg-config valgrind libhdf5-dev libgsl-dev hdf5-tools bats bats-assert bats-support
python3 python3-numpy python3-h5py python3-meshio lammps openmpi-bin gnuplot-nox groff-base time
zlib1g-dev paraview python3-paraview xvfb xauth gmsh libopenmpi-dev libhdf5-openmpi-dev"
missing=""
for p in $pkgs "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" ||
        missing="$missing $p"
done
[ -z "$missing" ] && exit 0
if [ "$(id -u)" -ne 0 ]; then
    echo "install-deps: missing Debian packages:$missing (run as root: apt-get install$missing)" >&2
    exit 1
fi
echo "install-deps: installing$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends $missing
