#!/usr/bin/env bash
# Builds the CIGI Class Library (CCL, unmodified third-party source) once into a cache outside
# the tracked tree, then the test host program `cigi-host` against it, and prints the host's
# path on stdout (progress goes to stderr).
#
#   tests/cigi-host/build.sh [native|s390x]
#
# native: the machine's own compiler and byte order. s390x: a big-endian host cross-built with
# s390x-linux-gnu-g++ and linked statically, to be run under qemu-s390x (CCL packs CIGI 3
# packets in the CPU's own byte order and never swaps outgoing ones, so a real big-endian
# host needs a big-endian CPU; see README.md here).
#
# The CCL source is $AERIE_CIGI_CCL, else ../shared/tools/cigi-ccl next to the repository, else
# the unmodified copy in third_party/cigi-ccl. The
# cache is <target>/cigi-ccl/<arch>-<key>/ (<target>: $CARGO_TARGET_DIR or target/), <key> a
# hash of the CCL's files, the compiler's version and the flags: a changed source or compiler
# builds a new library, an unchanged one is reused. Builds are atomic (a temporary folder
# renamed into place) and serialised by a lock, so an interrupted or concurrent build never
# leaves a half library.
set -euo pipefail

arch="${1:-native}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
if [ -n "${AERIE_CIGI_CCL:-}" ]; then
  ccl="$AERIE_CIGI_CCL"
elif [ -f "$root/../shared/tools/cigi-ccl/include/CigiHostSession.h" ]; then
  ccl="$root/../shared/tools/cigi-ccl"
else
  # The unmodified copy kept in the repository (third_party/cigi-ccl/VENDORED.md).
  ccl="$root/third_party/cigi-ccl"
fi
target="${CARGO_TARGET_DIR:-$root/target}"
case "$target" in /*) ;; *) target="$PWD/$target" ;; esac

fail() {
  echo "cigi-host build: $*" >&2
  exit 2
}

if [ ! -f "$ccl/include/CigiHostSession.h" ] || [ ! -d "$ccl/source" ]; then
  fail "the CIGI Class Library source was not found at $ccl (expected ../shared/tools/cigi-ccl next to the repository, see its PROVENANCE.md); set AERIE_CIGI_CCL to the folder holding its include/ and source/"
fi
ccl="$(cd "$ccl" && pwd)"

case "$arch" in
  native)
    cxx="${CXX:-g++}"
    ar="${AR:-ar}"
    link_flags=()
    ;;
  s390x)
    cxx=s390x-linux-gnu-g++
    ar=s390x-linux-gnu-ar
    # Static: qemu-s390x then needs no s390x dynamic loader or library path.
    link_flags=(-static)
    command -v qemu-s390x >/dev/null 2>&1 ||
      fail "qemu-s390x not found: install qemu-user (scripts/setup-debian.sh does) to run the big-endian host"
    ;;
  *) fail "unknown arch '$arch' (native or s390x)" ;;
esac
command -v "$cxx" >/dev/null 2>&1 ||
  fail "$cxx not found (arch $arch): scripts/setup-debian.sh installs g++ and g++-s390x-linux-gnu"

# PROVENANCE.md's flags; CIGI_LITTLE_ENDIAN only where the target CPU is little-endian (it
# selects the byte swapping of CIGI 1/2 packets, which are big-endian on the wire).
order="$("$cxx" -dM -E -x c++ /dev/null | sed -n 's/^#define __BYTE_ORDER__ //p')"
defines=()
case "$order" in
  __ORDER_LITTLE_ENDIAN__) defines+=(-DCIGI_LITTLE_ENDIAN) ;;
  __ORDER_BIG_ENDIAN__) ;;
  *) fail "$cxx: unknown byte order '$order'" ;;
esac
cflags=(-O1 -w "${defines[@]}")

hash_of() { sha256sum | cut -c1-16; }
key="$({
  "$cxx" --version | head -n1
  echo "${cflags[*]}"
  (cd "$ccl" && find source include -type f \( -name '*.cpp' -o -name '*.h' \) | LC_ALL=C sort | xargs sha256sum)
} | hash_of)"

dir="$target/cigi-ccl/$arch-$key"
lib="$dir/libcigicl.a"
mkdir -p "$target/cigi-ccl"
exec 9>"$target/cigi-ccl/.lock"
flock 9

if [ ! -f "$lib" ]; then
  mapfile -t sources < <(cd "$ccl" && find source -maxdepth 1 -name '*.cpp' | LC_ALL=C sort)
  total=${#sources[@]}
  tmp="$dir.tmp.$$"
  rm -rf "$tmp"
  mkdir -p "$tmp/obj"
  trap 'rm -rf "$tmp"' EXIT
  jobs="$(nproc 2>/dev/null || echo 2)"
  echo "cigi-ccl ($arch): compiling $total files of $ccl with $cxx ${cflags[*]}, $jobs at a time" >&2
  start=$SECONDS
  export ccl cxx tmp total arch
  export CFLAGS_LIST="${cflags[*]}"
  # One compiler per source file, $jobs at once; each finished object prints the count every
  # 20 files (and the last), so a CI log shows progress without a line per file.
  printf '%s\n' "${sources[@]}" | xargs -P "$jobs" -I{} bash -c '
    src="{}"; obj="$tmp/obj/$(basename "$src" .cpp).o"
    # shellcheck disable=SC2086
    "$cxx" $CFLAGS_LIST -I"$ccl/include" -c "$ccl/$src" -o "$obj" || exit 255
    n=$(find "$tmp/obj" -name "*.o" | wc -l)
    if [ $((n % 20)) -eq 0 ] || [ "$n" -eq "$total" ]; then
      echo "cigi-ccl ($arch): $n/$total compiled" >&2
    fi'
  "$ar" rcs "$tmp/libcigicl.a" "$tmp"/obj/*.o
  rm -rf "$tmp/obj"
  rm -rf "$dir"
  mv "$tmp" "$dir"
  trap - EXIT
  echo "cigi-ccl ($arch): $lib built in $((SECONDS - start)) s" >&2
fi

# The host program: rebuilt when its sources, the library or the flags change.
mapfile -t host_sources < <(find "$here" -maxdepth 1 -name '*.cpp' | LC_ALL=C sort)
host_flags=(-std=c++17 -O1 -Wall -Wextra)
host_key="$({
  echo "$key ${host_flags[*]} ${link_flags[*]:-}"
  cat "${host_sources[@]}" "$here"/*.h
} | hash_of)"
host="$dir/cigi-host-$host_key"
if [ ! -x "$host" ]; then
  echo "cigi-host ($arch): compiling ${#host_sources[@]} files" >&2
  # -isystem: the CCL's own headers are third-party code, not held to this project's warnings.
  "$cxx" "${host_flags[@]}" "${defines[@]}" -isystem "$ccl/include" "${host_sources[@]}" \
    "$lib" "${link_flags[@]}" -o "$host.tmp.$$"
  mv "$host.tmp.$$" "$host"
fi
echo "$host"
