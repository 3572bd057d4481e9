#!/usr/bin/env bash
# package_test.sh BUILD_DIR CMAKE CPACK VERSION: the install rules and the
# Debian package of a built tree (tools/package/). `cmake --install` into a
# scratch prefix lays out the programs, the unit, the data files and the
# example configuration; `cpack -G DEB` makes visvol_VERSION_ARCH.deb whose
# contents, control fields, conffiles and maintainer scripts are checked; the
# programs of a `dpkg -x` root run (--help, --version). Everything is written
# under one scratch directory, removed on exit (the install also rewrites
# BUILD_DIR/install_manifest.txt, as any install does).
set -euo pipefail
build=$1 cmake=$2 cpack=$3 version=$4
programs=(visvol visvol-console visvol-echo visvol-hapticsim)
unset DESTDIR
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
failures=0
fail() {
  echo "package_test: $*" >&2
  failures=$((failures + 1))
}

# 1. cmake --install: the layout under a prefix that is not /usr
prefix=$scratch/prefix
"$cmake" --install "$build" --prefix "$prefix" >"$scratch/install.log"
for p in "${programs[@]}"; do
  [[ -f $prefix/bin/$p && -x $prefix/bin/$p ]] || fail "install: bin/$p missing or not executable"
done
for f in lib/systemd/system/visvol-console.service etc/visvol/console.toml \
  share/doc/visvol/examples/console.toml share/visvol/haptic/haptic.dbc \
  share/visvol/dds/idl/visvol_msgs.idl share/visvol/dds/idl/ros2.idl share/visvol/dds/cyclone_loopback.xml \
  share/visvol/hapticsim/examples/grab_pull_release.txt; do
  [[ -f $prefix/$f ]] || fail "install: $f missing"
done
[[ -d $prefix/var/lib/visvol/terrains ]] || fail "install: var/lib/visvol/terrains/ missing"
scripts=$(find "$prefix/share/visvol/hapticsim/examples" -name '*.txt' 2>/dev/null | wc -l)
((scripts >= 3)) || fail "install: $scripts operator scripts in share/visvol/hapticsim/examples (3 or more expected)"
if cmp -s "$prefix/etc/visvol/console.toml" "$prefix/share/doc/visvol/examples/console.toml"; then :; else
  fail "install: etc/visvol/console.toml and the example in share/doc differ"
fi
grep -q '^ExecStart=/usr/bin/visvol-console --config /etc/visvol/console.toml' \
  "$prefix/lib/systemd/system/visvol-console.service" 2>/dev/null || fail "install: the unit's ExecStart is not the package's"

# 2. cpack -G DEB into the scratch directory
"$cpack" --config "$build/CPackConfig.cmake" -G DEB -B "$scratch/cpack" >"$scratch/cpack.log" 2>&1 || {
  cat "$scratch/cpack.log" >&2
  fail "cpack failed"
  exit 1
}
mapfile -t debs < <(find "$scratch/cpack" -maxdepth 1 -name "visvol_${version}_*.deb")
if ((${#debs[@]} != 1)); then
  cat "$scratch/cpack.log" >&2
  fail "cpack made ${#debs[@]} packages named visvol_${version}_*.deb (1 expected)"
  exit 1
fi
deb=${debs[0]}
echo "package_test: $(basename "$deb"), $(stat -c %s "$deb") bytes"

# 3. what the package holds (dpkg-deb -c), where Debian 12 wants it
dpkg-deb -c "$deb" | awk '{print $NF}' >"$scratch/contents"
for f in ./usr/bin/visvol-console ./usr/bin/visvol ./usr/bin/visvol-echo ./usr/bin/visvol-hapticsim \
  ./lib/systemd/system/visvol-console.service ./etc/visvol/console.toml ./var/lib/visvol/terrains/ \
  ./usr/share/doc/visvol/examples/console.toml ./usr/share/visvol/haptic/haptic.dbc \
  ./usr/share/visvol/dds/idl/visvol_msgs.idl ./usr/share/visvol/dds/cyclone_loopback.xml \
  ./usr/share/visvol/hapticsim/examples/grab_pull_release.txt; do
  grep -qxF "$f" "$scratch/contents" || fail "package: $f not listed by dpkg-deb -c"
done
if grep -E '^\./usr/(etc|local|var)/|^\./usr/lib/systemd/' "$scratch/contents" >&2; then
  fail "package: files above under /usr that belong to /etc, /var or /lib/systemd"
fi

# 4. control fields, conffiles and maintainer scripts (dpkg-deb -f, -I, -e)
[[ $(dpkg-deb -f "$deb" Package) == visvol ]] || fail "package: Package is not visvol"
[[ $(dpkg-deb -f "$deb" Version) == "$version" ]] || fail "package: Version is not $version"
depends=$(dpkg-deb -f "$deb" Depends)
echo "package_test: Depends: $depends"
adduser_re='(^|, )adduser(,|$)' libc_re='(^|, )libc6 \(>= '
[[ $depends =~ $adduser_re ]] || fail "package: Depends lacks adduser"
[[ $depends =~ $libc_re ]] || fail "package: Depends lacks libc6 (dpkg-shlibdeps did not run?)"
conffiles=$(dpkg-deb -I "$deb" conffiles 2>/dev/null) || fail "package: no conffiles"
[[ $conffiles == /etc/visvol/console.toml ]] || fail "package: conffiles is '$conffiles', not /etc/visvol/console.toml"
dpkg-deb -e "$deb" "$scratch/control"
for s in postinst prerm postrm; do
  if [[ ! -x $scratch/control/$s ]]; then
    fail "package: no executable $s"
  elif ! sh -n "$scratch/control/$s"; then
    fail "package: $s is not valid sh"
  fi
done
grep -q 'adduser --system' "$scratch/control/postinst" 2>/dev/null || fail "package: postinst makes no system user"

# 5. the programs run from a root unpacked with dpkg -x (stripped)
root=$scratch/root
dpkg -x "$deb" "$root"
[[ -d $root/var/lib/visvol/terrains ]] || fail "dpkg -x: var/lib/visvol/terrains/ missing"
if help=$("$root/usr/bin/visvol-console" --help); then
  [[ $help == *"--pack"* && $help == *"--config"* ]] || fail "visvol-console --help does not list --pack and --config"
else
  fail "visvol-console --help exited $?"
fi
for p in "${programs[@]}"; do
  if out=$("$root/usr/bin/$p" --version); then
    [[ $out == "$p $version "* ]] || fail "$p --version printed '$out'"
  else
    fail "$p --version exited $?"
  fi
  [[ $(file -b "$root/usr/bin/$p") == *", stripped"* ]] || fail "package: usr/bin/$p is not stripped"
done

if ((failures > 0)); then
  echo "package_test: $failures failures" >&2
  exit 1
fi
echo "package_test: install layout, package and programs as expected"
