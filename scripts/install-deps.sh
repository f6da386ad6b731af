#!/usr/bin/env bash
# Installs, from Debian 12 packages, whatever pidlab needs and the machine
# lacks. Safe to run again: it installs only missing packages.
#   scripts/install-deps.sh [--with-java]   (--with-java: JDK for tools/lcm-spy)
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev
  gnuplot-nox
  iproute2 util-linux python3
)
for arg in "$@"; do
  case "$arg" in
    --with-java) packages+=(default-jdk-headless liblcm-java) ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) echo "install-deps.sh: error: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
