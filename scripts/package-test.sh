#!/usr/bin/env bash
# Tests installing Arbiter as a user does (docs/plugins.md, docs/deploy.md), from a fresh clone of
# this repository's HEAD:
#   1. the quick start, then the SDK: scripts/demo.sh, then `cmake --install build/release --prefix
#      P` as docs/plugins.md gives it; tests/consumer builds against P and its config runs;
#   2. the Debian packages: the DDS plugin built too, then `cpack -G DEB` in build/release;
#   3. a fresh Debian bookworm root (debootstrap --variant=minbase): `apt-get install
#      ./arbiter*.deb ./python3-arbiter*.deb` pulls in what the packages declare, the soccer demo
#      runs from /usr, Debian's python3 imports the module and runs it, and tests/consumer builds
#      against the installed arbiter-dev and runs.
# Needs root (debootstrap, chroot) and the Debian mirror of this machine's apt sources. It takes
# about 25 minutes on a busy 2-core machine (a release build, a Debian root the first time), so
# it is not part of .ci/run.
#   scripts/package-test.sh [WORK_DIR]     default /tmp/arbiter-package-test; the Debian root is
#                                           kept there (WORK_DIR/root) for the next run
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
work=${1:-/tmp/arbiter-package-test}
root=$work/root
if [[ $(id -u) -ne 0 ]]; then
  echo "package-test: needs root (debootstrap and chroot)" >&2
  exit 1
fi
"$top/scripts/install-deps.sh" debootstrap dpkg-dev
command -v ccache >/dev/null && export CMAKE_CXX_COMPILER_LAUNCHER=ccache

step() { echo "== package-test: $*"; }
# Fails with `what` and the output unless `pattern` (grep -E) is in it.
expect() {
  local what=$1 pattern=$2 output=$3
  if ! grep -qE -- "$pattern" <<<"$output"; then
    printf '%s\n' "$output" | tail -n 40 >&2
    echo "package-test: FAILED: $what: no '$pattern' in the output above" >&2
    exit 1
  fi
}

step "a fresh clone of HEAD in $work/src"
rm -rf "$work/src" "$work/sdk" "$work/consumer"
mkdir -p "$work"
git clone -q "$top" "$work/src"
cd "$work/src"

step "the quick start: scripts/demo.sh"
output=$(scripts/demo.sh 2>&1)
expect "scripts/demo.sh" "goal!" "$output"

step "the SDK: cmake --install build/release --prefix $work/sdk"
cmake --install build/release --prefix "$work/sdk" >/dev/null
cmake -S tests/consumer -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$work/sdk" --log-level=WARNING >/dev/null
cmake --build "$work/consumer" >/dev/null
output=$("$work/sdk/bin/arbiter" --plugin-path "$work/consumer" run tests/consumer/patrol.yaml \
    --steps 40 2>&1)
expect "the consumer plugin with the SDK" "watch: finished" "$output"
output=$("$work/sdk/bin/arbiter" run configs/soccer/walk_and_kick.yaml --steps 220 2>&1)
expect "the demo with the SDK's arbiter" "goal!" "$output"

if command -v systemd-analyze >/dev/null; then
  step "docs/deploy.md's systemd unit: systemd-analyze verify"
  mkdir -p "$work/unit"
  awk '/^```ini/{f=1; next} /^```/{f=0} f' docs/deploy.md |
      sed "s#/usr/bin/arbiter#$work/sdk/bin/arbiter#" >"$work/unit/arbiter.service"
  output=$(systemd-analyze verify "$work/unit/arbiter.service" 2>&1)
  if [[ -n $output ]]; then
    echo "$output" >&2
    echo "package-test: FAILED: systemd-analyze verify" >&2
    exit 1
  fi
fi

step "the Debian packages: cpack -G DEB"
cmake --build --preset release --target arbiter soccer dds arbiter_python >/dev/null
(cd build/release && cpack -G DEB >/dev/null)
ls -l build/release/{,python3-}arbiter*.deb
for deb in build/release/{,python3-}arbiter*.deb; do
  dpkg-deb --field "$deb" Package Depends
done

step "a fresh Debian root in $root"
if [[ ! -x $root/usr/bin/apt-get ]]; then
  mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources)
  debootstrap --variant=minbase bookworm "$root" "$mirror" >/dev/null
fi
cp /etc/apt/sources.list.d/debian.sources "$root/etc/apt/sources.list.d/"
rm -f "$root/etc/apt/sources.list"
for mount in proc sys dev; do
  mountpoint -q "$root/$mount" || mount --bind "/$mount" "$root/$mount"
done
trap 'for m in dev sys proc; do umount "$root/$m" 2>/dev/null || true; done' EXIT
# Start from a root without Arbiter, whatever an earlier run left.
chroot "$root" dpkg --purge python3-arbiter arbiter-dev arbiter-plugins arbiter >/dev/null 2>&1 ||
    true
rm -rf "$root/packages" "$root/consumer" "$root/consumer-build"
mkdir -p "$root/packages"
cp build/release/{,python3-}arbiter*.deb "$root/packages/"
cp -r tests/consumer "$root/consumer"

in_root() { chroot "$root" env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root bash -c "$1"; }
step "apt-get install ./arbiter*.deb"
in_root "apt-get -q update >/dev/null && cd /packages &&
         DEBIAN_FRONTEND=noninteractive apt-get -q -y install ./*.deb >/dev/null"
step "the demo from /usr"
output=$(in_root "arbiter run /usr/share/arbiter/configs/soccer/walk_and_kick.yaml --steps 220" 2>&1)
expect "the demo from /usr" "goal!" "$output"
output=$(in_root "arbiter plugins" 2>&1)
expect "the installed plugins" "dds.Bridge" "$output"
step "the Python module from /usr"
output=$(in_root "python3 -c 'import arbiter
program = arbiter.load(\"/usr/share/arbiter/configs/soccer/walk_and_kick.yaml\")
manager = program.manager()
manager.step(220)
print(\"stepped\", manager.steps, \"steps\")'" 2>&1)
expect "the Python module from /usr" "stepped 220 steps" "$output"
step "tests/consumer against the installed arbiter-dev"
in_root "DEBIAN_FRONTEND=noninteractive apt-get -q -y install --no-install-recommends g++ make >/dev/null"
output=$(in_root "cmake -S /consumer -B /consumer-build --log-level=WARNING &&
                  cmake --build /consumer-build &&
                  arbiter --plugin-path /consumer-build run /consumer/patrol.yaml --steps 40" 2>&1)
expect "tests/consumer built against /usr" "watch: finished" "$output"
step "ok"
