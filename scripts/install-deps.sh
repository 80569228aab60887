#!/usr/bin/env bash
# Installs everything mebake needs to build, test and benchmark, from Debian 12 packages only.
# Safe to re-run; skips apt entirely when every package is already present.
set -euo pipefail

PKGS=(
  build-essential cmake ninja-build pkg-config git
  libopenmesh-dev libembree-dev libtbb-dev liblz4-dev libopenexr-dev libcli11-dev
  libeigen3-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libpng-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-14 libclang-rt-14-dev
  time openexr
  libcpp-httplib-dev libmeshoptimizer-dev chromium
  tmux  # tests/e2e/progress_tmux_test.cpp: progress lines as a terminal shows them
)

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# The viewer embeds three.js from npm at build time and its test drives headless Chromium
# with node. Any node >= 18 with npm will do (Debian's, or one installed otherwise: adding
# Debian's npm beside a node that bundles its own would conflict), so check the commands.
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages (and node, npm) present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get -o DPkg::Lock::Timeout=600 update -qq
$SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}"
