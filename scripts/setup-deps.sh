#!/usr/bin/env bash
# Installs the Debian packages rsph needs, only those that are missing.
# Idempotent and quiet when everything is present; runs `apt-get update` once when it must install.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libboost-dev libboost-program-options-dev
  libfmt-dev catch2 libbenchmark-dev libhdf5-dev
  python3 python3-matplotlib python3-numpy python3-h5py python3-meshio
  clang-format
  voro++-dev
  openmpi-bin libopenmpi-dev libtrilinos-zoltan-dev libhdf5-openmpi-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

[ ${#missing[@]} -eq 0 ] && exit 0

echo "rsph: installing missing Debian packages: ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
