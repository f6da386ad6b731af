#!/usr/bin/env bash
# Installs, from Debian 12 packages, whatever pidlab needs and the machine
# lacks, then the page's npm packages (package.json, pinned by package-lock.json:
# uPlot, embedded in pidlab serve; puppeteer-core, for the browser tests) into
# node_modules/ with npm ci. Safe to run again: it installs only what is missing.
#   scripts/install-deps.sh [--no-java] [--pil]
#   --no-java: skip the JDK that tools/lcm-spy needs
#   --pil: also the processor-in-the-loop toolchain (docs/pil.md): gcc-arm-none-eabi,
#          libnewlib-arm-none-eabi and qemu-system-arm (about 600 MB installed)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config clang
  libeigen3-dev libceres-dev
  liblcm-dev liblcm-bin libglib2.0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libsodium-dev
  gnuplot-nox libboost-dev pybind11-dev python3-dev
  iproute2 util-linux python3 python3-numpy python3-scipy bc
  chromium
  default-jdk-headless liblcm-java
)
no_java=0
for arg in "$@"; do
  case "$arg" in
    --no-java) no_java=1 ;;
    --pil) packages+=(gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm) ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
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
# Node.js and npm: the machine's own if it has them (any version >= 18), else Debian's.
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The npm packages, at the versions package-lock.json pins; npm ci again only when the lock changed
# or a package's files are gone (the build embeds uPlot's dist; the browser tests need puppeteer-core).
root=$(cd "$(dirname "$0")/.." && pwd)
if ! cmp -s "$root/package-lock.json" "$root/node_modules/.pidlab-lock.json" ||
   [ ! -f "$root/node_modules/uplot/dist/uPlot.iife.min.js" ] ||
   [ ! -f "$root/node_modules/puppeteer-core/lib/cjs/puppeteer/puppeteer-core.js" ]; then
  echo "install-deps: npm ci (uplot, puppeteer-core; no browser is downloaded)"
  (cd "$root" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
  cp "$root/package-lock.json" "$root/node_modules/.pidlab-lock.json"
else
  echo "install-deps: npm packages present"
fi
