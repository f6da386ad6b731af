#!/usr/bin/env bash
# Installs, from Debian 12 packages, whatever pidlab needs and the machine
# lacks. Safe to run again: it installs only missing packages.
#   scripts/install-deps.sh [--no-java]   (--no-java: skip the JDK that tools/lcm-spy needs)
set -euo pipefail

packages=(
  build-essential cmake pkg-config clang
  libeigen3-dev libceres-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libsodium-dev
  gnuplot-nox libboost-dev pybind11-dev python3-dev
  iproute2 util-linux python3 python3-numpy python3-scipy bc
  default-jdk-headless liblcm-java
)
no_java=0
for arg in "$@"; do
  case "$arg" in
    --no-java) no_java=1 ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) echo "install-deps.sh: error: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

if [ "$no_java" -eq 1 ]; then
  packages=("${packages[@]/default-jdk-headless}"); packages=("${packages[@]/liblcm-java}")
fi
missing=()
for p in "${packages[@]}"; do
  [ -n "$p" ] || continue
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
