#!/usr/bin/env bash
# Installs the Debian packages phymul needs, only those missing.
# usage: install-deps.sh build|demo|sanitize
set -euo pipefail
build_pkgs=(cmake make g++ libeigen3-dev libyaml-cpp-dev libcli11-dev libfmt-dev libgmsh-dev
  libgtest-dev libgmock-dev libbenchmark-dev python3-meshio python3-numpy
  pybind11-dev python3-dev python3-pytest python3-yaml python3-distributed python3-pandas
  python3-matplotlib libwebsocketpp-dev libasio-dev nlohmann-json3-dev libpugixml-dev zlib1g-dev
  python3-nibabel python3-vtk9)
# (python3-vtk9: the VTK XML tests write their files with VTK's own writers.)
demo_pkgs=(xvfb xauth)
# The sanitized build and the fuzzers (clang, its sanitizer and libFuzzer runtimes, its OpenMP).
sanitize_pkgs=(clang-14 libclang-rt-14-dev libomp-14-dev)
# Wanted but not required: the tests that need them say loudly that they were skipped (the
# live view's page needs node, npm and esbuild to build, chromium to test). "package:command":
# present when the command is, whoever installed it (nodesource's nodejs carries its own npm,
# which Debian's npm package conflicts with).
optional_pkgs=(calculix-ccx nodejs:node npm:npm esbuild:esbuild chromium:chromium)
case "${1:-build}" in
  build) want=("${build_pkgs[@]}") ;;
  demo) want=("${build_pkgs[@]}" "${demo_pkgs[@]}") ;;
  sanitize) want=("${build_pkgs[@]}" "${sanitize_pkgs[@]}") ;;
  *) echo "install-deps.sh: unknown set '$1' (allowed: build, demo, sanitize)" >&2; exit 2 ;;
esac

missing_of() {
  local p
  for p in "$@"; do
    if [[ $p == *:* ]]; then
      command -v "${p#*:}" >/dev/null || echo "${p%%:*}"
    else
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
    fi
  done
}
mapfile -t missing < <(missing_of "${want[@]}")
mapfile -t missing_optional < <(missing_of "${optional_pkgs[@]}")
[ ${#missing[@]} -eq 0 ] && [ ${#missing_optional[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -ne 0 ]; then
  if [ ${#missing[@]} -gt 0 ]; then
    echo "phymul needs these Debian packages: ${missing[*]}" >&2
    echo "run as root: apt-get update && apt-get install -y ${missing[*]} ${missing_optional[*]}" >&2
    exit 1
  fi
  echo "warning: optional packages missing (${missing_optional[*]}); as root: apt-get install -y ${missing_optional[*]}" >&2
  exit 0
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq >/dev/null
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
for p in "${missing_optional[@]}"; do  # one at a time: one that fails does not stop the rest
  echo "installing (optional): $p"
  apt-get install -y -qq --no-install-recommends "$p" >/dev/null ||
    echo "warning: could not install $p; the tests that need it will be skipped" >&2
done
