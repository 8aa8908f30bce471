#!/usr/bin/env bash
# Installs the Debian packages Arbiter needs to build and test, only those that are missing.
# Fast and silent when everything is present; runs apt-get as root, or through sudo otherwise.
set -euo pipefail

packages=(cmake g++ ninja-build pkg-config libyaml-cpp-dev nlohmann-json3-dev libfmt-dev libzstd-dev zlib1g-dev
          libspdlog-dev catch2 libcli11-dev libbenchmark-dev libvalijson-dev
          cyclonedds-dev cyclonedds-tools libcpp-httplib-dev esbuild libwebsocketpp-dev libasio-dev
          python3-dev pybind11-dev)
# The web app's build (web/) runs npm. Looked for by command, so that a Node.js installed some
# other way (whose npm is not Debian's package) counts.
command -v node >/dev/null || packages+=(nodejs)
command -v npm >/dev/null || packages+=(npm)
# Arguments: more packages the caller needs (scripts/test.sh passes the tools only tests use).
packages+=("$@")

# dpkg-query prints nothing for a package it has never heard of, so anything not listed as
# installed is missing.
installed=$(dpkg-query -W -f='${Package} ${db:Status-Status}\n' "${packages[@]}" 2>/dev/null |
            awk '$2 == "installed" {print $1}' || true)
missing=()
for package in "${packages[@]}"; do
  grep -qx -- "$package" <<<"$installed" || missing+=("$package")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

as_root=()
if [[ $(id -u) -ne 0 ]]; then
  if ! command -v sudo >/dev/null; then
    echo "install-deps: missing ${missing[*]}; run this script as root (sudo is not available)" >&2
    exit 1
  fi
  as_root=(sudo)
  [[ -t 0 ]] || as_root+=(-n)
fi

echo "install-deps: installing ${missing[*]}"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
apt=("${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -q -y -o DPkg::Lock::Timeout=300)
if ! { "${apt[@]}" update && "${apt[@]}" install --no-install-recommends "${missing[@]}"; } \
    >"$log" 2>&1; then
  cat "$log" >&2
  echo "install-deps: apt-get failed" >&2
  exit 1
fi
