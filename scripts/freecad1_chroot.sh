#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# FreeCAD 1.x beside the host's FreeCAD 0.20: a Debian 13 (trixie) chroot with FreeCAD 1.0
# (Python 3.13, OpenCASCADE 7.8) and what building and testing FemBspTet needs, the checkout
# bind-mounted at /fembsptet, and the extension built for the chroot's Python into build-freecad1/
# (the module lands in FemBspTet/ beside the host's one: the file names differ by their ABI tag).
#
#   scripts/freecad1_chroot.sh                 make or reuse the chroot, build the extension
#   scripts/freecad1_chroot.sh -- CMD [ARG...] the same, then run CMD inside the chroot in the checkout
#
# The chroot lives at $FEMBSPTET_FREECAD1_ROOT (default /var/cache/fembsptet/trixie) and is reused
# when complete. Debian 13 has no CalculiX package: the host's ccx is copied in with the libraries it
# links and runs through the host's dynamic loader (/usr/local/bin/ccx inside the chroot). Needs root
# (debootstrap, chroot, mount) and the host's ccx (calculix-ccx, scripts/setup.sh installs it).
# Every mount made here is undone on exit, whatever the exit.
set -euo pipefail
SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
CHROOT=${FEMBSPTET_FREECAD1_ROOT:-/var/cache/fembsptet/trixie}
MIRROR=${FEMBSPTET_DEBIAN_MIRROR:-http://deb.debian.org/debian}
SUITE=trixie
INSIDE=/fembsptet                     # the checkout inside the chroot
BUILD=build-freecad1                  # build directory, relative to the checkout
HOST_CCX_DIR=/opt/fembsptet-host-ccx  # the host's ccx and its libraries, inside the chroot
NICE=(nice -n 19)

PACKAGES=(
  # FreeCAD 1.0 and its FEM peers
  freecad-python3 gmsh python3-gmsh tetgen python3-netgen
  # build
  cmake ninja-build g++ pybind11-dev python3-dev libgmp-dev libtbb-dev
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev libocct-data-exchange-dev
  libfontconfig-dev  # OpenCASCADE 7.8's STEP toolkit links its visualization ones, which link fontconfig
  # tests and the Python side
  python3-numpy python3-pytest python3-meshio python3-rich python3-matplotlib
  # the offscreen GUI test
  xauth
  time
)

START=$SECONDS
say() { echo "freecad1 [$((SECONDS - START)) s]: $*" >&2; }
die() { echo "freecad1: error: $*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || die "needs root (debootstrap, chroot and bind mounts); run it with sudo"
case $CHROOT in
  /?*/?*) CHROOT=${CHROOT%/} ;;
  *) die "FEMBSPTET_FREECAD1_ROOT must be an absolute path two levels deep at least, not '$CHROOT'" ;;
esac
command -v ccx >/dev/null || die "the host has no ccx (CalculiX); install calculix-ccx (scripts/setup.sh does)"

CMD=()
if [ $# -gt 0 ]; then
  [ "$1" = "--" ] || die "usage: $0 [-- COMMAND [ARG...]]"
  shift
  CMD=("$@")
fi

# ---- one run at a time per chroot; mounts undone on every exit ---------------------------------
mkdir -p "$(dirname "$CHROOT")"
exec 9>"$CHROOT.lock"
if ! flock -n 9; then
  say "waiting for another run that uses $CHROOT"
  flock 9
fi
MOUNTED=()
cleanup() {
  local i
  for ((i = ${#MOUNTED[@]} - 1; i >= 0; i--)); do
    umount "${MOUNTED[i]}" 2>/dev/null || umount -l "${MOUNTED[i]}" 2>/dev/null ||
      echo "freecad1: warning: could not unmount ${MOUNTED[i]}" >&2
  done
  MOUNTED=()
}
CHILD=
stop() {  # on INT/TERM: end the command running in the chroot, then exit (cleanup runs)
  if [ -n "$CHILD" ]; then kill -TERM "$CHILD" 2>/dev/null; wait "$CHILD" 2>/dev/null; fi
  exit "$1"
}
trap cleanup EXIT
trap 'stop 130' INT
trap 'stop 143' TERM

mount_into() {  # mount_into TARGET MOUNT-ARGS...: mount unless something is mounted there already
  local target=$CHROOT$1
  shift
  mkdir -p "$target"
  if mountpoint -q "$target"; then
    # another run uses this chroot at the same time; leave its mount alone
    return
  fi
  mount "$@" "$target"
  MOUNTED+=("$target")
}

mount_system() {
  mount_into /proc -t proc proc
  mount_into /sys -t sysfs sysfs
  mount_into /dev --bind /dev
  mount_into /dev/pts --bind /dev/pts
}

# A command in the chroot with a clean environment; FEMBSPTET_CORE_TOOL and FEMBSPTET_BUILD_DIR
# name the chroot's build, never the host's build/.
CHROOT_CMD=(env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
  LANG=C.UTF-8 TERM="${TERM:-dumb}" DEBIAN_FRONTEND=noninteractive
  FEMBSPTET_BUILD_DIR="$INSIDE/$BUILD" FEMBSPTET_CORE_TOOL="$INSIDE/$BUILD/cpp_module/bsptet_mesh"
  "${NICE[@]}" chroot "$CHROOT")
in_chroot() { "${CHROOT_CMD[@]}" "$@"; }

# ---- 1. the base system ------------------------------------------------------------------------
if [ -f "$CHROOT/.fembsptet-base-complete" ]; then
  say "reusing the $SUITE chroot at $CHROOT"
else
  if ! command -v debootstrap >/dev/null; then
    say "installing debootstrap on the host"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends debootstrap ||
      { apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends debootstrap; } ||
      die "could not install debootstrap"
  fi
  if [ -e "$CHROOT" ]; then
    # only what an interrupted debootstrap left (its debootstrap/ folder), or an empty folder
    if [ ! -d "$CHROOT/debootstrap" ] && [ -n "$(ls -A "$CHROOT" 2>/dev/null)" ]; then
      die "$CHROOT exists but is neither a chroot made here nor empty; move it away or set FEMBSPTET_FREECAD1_ROOT"
    fi
    if awk -v r="$CHROOT/" 'index($2, r) == 1 {found = 1} END {exit !found}' /proc/mounts; then
      die "something is still mounted under $CHROOT; unmount it first"
    fi
    say "removing the incomplete chroot at $CHROOT (an interrupted debootstrap)"
    rm -rf --one-file-system "$CHROOT"
  fi
  say "debootstrap $SUITE into $CHROOT (from $MIRROR)"
  "${NICE[@]}" debootstrap --variant=minbase "$SUITE" "$CHROOT" "$MIRROR" ||
    die "debootstrap failed (see $CHROOT/debootstrap/debootstrap.log)"
  # no services start inside the chroot
  printf '#!/bin/sh\nexit 101\n' >"$CHROOT/usr/sbin/policy-rc.d"
  chmod +x "$CHROOT/usr/sbin/policy-rc.d"
  touch "$CHROOT/.fembsptet-base-complete"
fi
cp -L /etc/resolv.conf "$CHROOT/etc/resolv.conf" 2>/dev/null || true

# ---- 2. packages -------------------------------------------------------------------------------
mount_system
installed=$(in_chroot dpkg-query -W -f='${Package} ${Status}\n' "${PACKAGES[@]}" 2>/dev/null || true)
missing=()
for p in "${PACKAGES[@]}"; do
  grep -qx "$p install ok installed" <<<"$installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  say "installing in the chroot: ${missing[*]}"
  in_chroot apt-get update -q || die "apt-get update failed inside the chroot"
  in_chroot apt-get install -y -q --no-install-recommends "${missing[@]}" ||
    die "apt-get install failed inside the chroot"
  in_chroot apt-get clean
else
  say "the chroot's packages are all installed"
fi

# ---- 3. the host's ccx ---------------------------------------------------------------------------
host_ccx=$(readlink -f "$(command -v ccx)")
stamp="$host_ccx $(stat -c '%s %Y' "$host_ccx")"
if [ "$(cat "$CHROOT$HOST_CCX_DIR/stamp" 2>/dev/null)" != "$stamp" ]; then
  say "copying the host's ccx ($host_ccx) and its libraries into $HOST_CCX_DIR"
  rm -rf "$CHROOT$HOST_CCX_DIR"
  mkdir -p "$CHROOT$HOST_CCX_DIR/lib"
  cp -L "$host_ccx" "$CHROOT$HOST_CCX_DIR/ccx"
  loader=
  while read -r lib; do
    cp -L "$lib" "$CHROOT$HOST_CCX_DIR/lib/"
    case $lib in */ld-linux*) loader=$(basename "$lib") ;; esac
  done < <(ldd "$host_ccx" | awk '/=> \//{print $3} /^\t\/[^ ]*ld-linux/{print $1}')
  [ -n "$loader" ] || die "could not find the dynamic loader of $host_ccx (ldd)"
  cat >"$CHROOT/usr/local/bin/ccx" <<EOF
#!/bin/sh
# CalculiX from the host system: its binary, libraries and dynamic loader (Debian 13 has no ccx).
exec $HOST_CCX_DIR/lib/$loader --library-path $HOST_CCX_DIR/lib $HOST_CCX_DIR/ccx "\$@"
EOF
  chmod +x "$CHROOT/usr/local/bin/ccx"
  echo "$stamp" >"$CHROOT$HOST_CCX_DIR/stamp"
fi
ccx_version=$(in_chroot sh -c 'cd /tmp && ccx -v' 2>&1 || true)  # ccx -v exits with 201
case $ccx_version in
  *"This is Version"*) ;;
  *) die "the host's ccx does not run inside the chroot: ${ccx_version:-no output} (try: chroot $CHROOT ccx -v)" ;;
esac

# ---- 4. the checkout and the build ------------------------------------------------------------------
mount_into "$INSIDE" --bind "$SRC"
say "building the extension for the chroot's Python in $BUILD/"
if [ ! -f "$SRC/$BUILD/CMakeCache.txt" ]; then
  in_chroot cmake -S "$INSIDE" -B "$INSIDE/$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DPython_EXECUTABLE=/usr/bin/python3 -DFEMBSPTET_BUILD_TESTS=OFF >/dev/null ||
    die "cmake configure failed in the chroot"
fi
in_chroot cmake --build "$INSIDE/$BUILD" -j1 || die "the build failed in the chroot"
suffix=$(in_chroot /usr/bin/python3 -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
for module in _bsptet _bsptet_cad; do
  [ -f "$SRC/FemBspTet/$module$suffix" ] || die "the build made no FemBspTet/$module$suffix"
done
say "built FemBspTet/_bsptet$suffix and _bsptet_cad$suffix"

# ---- 5. the command ----------------------------------------------------------------------------------
if ((${#CMD[@]})); then
  say "running in the chroot: ${CMD[*]}"
  # in the background and waited for, so that INT/TERM reach the traps at once
  # (a simple command: its process becomes the command itself, which TERM then reaches)
  "${CHROOT_CMD[@]}" sh -c 'cd "$0" && exec "$@"' "$INSIDE" "${CMD[@]}" &
  CHILD=$!
  status=0
  wait "$CHILD" || status=$?
  CHILD=
  exit $status
fi
