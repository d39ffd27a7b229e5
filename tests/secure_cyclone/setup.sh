#!/usr/bin/env bash
# A secured Cyclone DDS peer for the DDS Security interop test (tests/system/security.rs):
# Debian's Cyclone DDS (libddsc0debian ships the DDS-Security builtin plugins: libdds_security_auth,
# _ac, _crypto, which PyPI's cyclonedds wheels leave out) and the Python binding of the same
# version built from source against it, in its own virtual environment .venv-secure-cyclone (the
# wheel in .venv carries a newer Cyclone of its own, without the plugins).
#
# Writes .venv-secure-cyclone/plugins-dir: where the security plugins are (LD_LIBRARY_PATH for the
# peer). Run by tests/run; by hand: `tests/secure_cyclone/setup.sh` (root for apt-get).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cd "$root"
venv=.venv-secure-cyclone

# Debian's Cyclone DDS, and Python's headers to build the binding's C extension
need=()
dpkg-query -W -f='${Status}' cyclonedds-dev 2>/dev/null | grep -q "install ok installed" || need+=(cyclonedds-dev)
[ -f "$(python3 -c 'import sysconfig; print(sysconfig.get_paths()["include"])')/Python.h" ] || need+=(python3-dev)
if [ "${#need[@]}" -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need[@]}"
  else
    echo "tests/secure_cyclone/setup.sh: the secured Cyclone DDS peer needs Debian's ${need[*]}; install them (apt-get install ${need[*]}) and run again" >&2
    exit 2
  fi
fi
plugin=$(dpkg -L libddsc0debian | grep '/libdds_security_auth\.so$' | head -n1)
[ -n "$plugin" ] || { echo "tests/secure_cyclone/setup.sh: libddsc0debian has no libdds_security_auth.so" >&2; exit 1; }
version=$(dpkg-query -W -f='${Version}' libddsc0debian | sed 's/-[^-]*$//')
want="cyclonedds $version $(sha256sum "$0" | cut -d' ' -f1)"
if [ "$(cat "$venv/.stamp" 2>/dev/null)" = "$want" ]; then exit 0; fi

rm -rf "$venv"
python3 -m venv "$venv"
# The binding's build looks for CYCLONEDDS_HOME/{lib,include}; Debian spreads them over
# /usr/lib/<arch> and /usr/include.
home="$root/$venv/cyclonedds-home"
libdir=$(dirname "$(dpkg -L libddsc0debian | grep '/libddsc\.so\.' | head -n1)")
mkdir -p "$home/lib" "$home/bin"
ln -s /usr/include "$home/include"
for f in "$libdir"/libddsc.so* "$libdir"/libcycloneddsidl.so*; do ln -s "$f" "$home/lib/"; done
[ -d "$libdir/cmake" ] && ln -s "$libdir/cmake" "$home/lib/cmake"
CYCLONEDDS_HOME="$home" "$venv/bin/pip" install --quiet --disable-pip-version-check \
  --no-binary cyclonedds "cyclonedds==$version"
dirname "$plugin" > "$venv/plugins-dir"
echo "$want" > "$venv/.stamp"
